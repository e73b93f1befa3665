#include "gmm_localization/core/matching/hill_climb.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace gmm_localization {

std::string HillClimbOptions::validate() const {
  const std::array<double, 10> positive = {max_xy_m,
                                           max_yaw_rad,
                                           max_z_m,
                                           max_roll_pitch_rad,
                                           initial_xy_step_m,
                                           initial_z_step_m,
                                           initial_angle_step_rad,
                                           min_xy_step_m,
                                           min_z_step_m,
                                           min_angle_step_rad};
  for (double v : positive) {
    if (!(v >= 0.0 && std::isfinite(v))) return "hill-climb limits and steps must be >= 0";
  }
  if (max_evaluations < 1) return "max_evaluations must be >= 1";
  return {};
}

namespace {
enum Axis { kX, kY, kZ, kRoll, kPitch, kYaw, kAxes };

double& coord(Pose6& p, int a) {
  switch (a) {
    case kX:
      return p.x;
    case kY:
      return p.y;
    case kZ:
      return p.z;
    case kRoll:
      return p.roll;
    case kPitch:
      return p.pitch;
    default:
      return p.yaw;
  }
}
}  // namespace

/// One pattern search from `start`, constrained to the box around `centre`; `kept` (optional)
/// is told each time the climb moves to the pose just scored.
HillClimbOutcome climb(const std::function<double(const Pose6&)>& score,
                       const std::function<void()>& kept, const Pose6& start, const Pose6& centre,
                       const HillClimbOptions& o) {
  const std::array<double, kAxes> limit = {
      o.max_xy_m, o.max_xy_m, o.max_z_m, o.max_roll_pitch_rad, o.max_roll_pitch_rad, o.max_yaw_rad};
  std::array<double, kAxes> step = {o.initial_xy_step_m,      o.initial_xy_step_m,
                                    o.initial_z_step_m,       o.initial_angle_step_rad,
                                    o.initial_angle_step_rad, o.initial_angle_step_rad};
  const std::array<double, kAxes> min_step = {o.min_xy_step_m,      o.min_xy_step_m,
                                              o.min_z_step_m,       o.min_angle_step_rad,
                                              o.min_angle_step_rad, o.min_angle_step_rad};
  HillClimbOutcome out;
  out.pose = start;
  out.score_start = out.score = score(start);
  if (kept) kept();
  out.evaluations = 1;
  Pose6 start_copy = centre;
  bool any_step_left = true;
  while (any_step_left && out.evaluations < o.max_evaluations) {
    bool improved = false;
    for (int a = 0; a < kAxes && out.evaluations < o.max_evaluations; ++a) {
      if (step[a] < min_step[a] || limit[a] <= 0.0) continue;
      for (double sign : {+1.0, -1.0}) {
        Pose6 trial = out.pose;
        double& v = coord(trial, a);
        const double origin = coord(start_copy, a);
        v += sign * step[a];
        if (std::abs(v - origin) > limit[a] + 1e-12) continue;
        const double s = score(trial);
        ++out.evaluations;
        if (s > out.score) {
          out.score = s;
          out.pose = trial;
          if (kept) kept();
          improved = true;
          break;
        }
      }
    }
    if (!improved) {
      any_step_left = false;
      for (int a = 0; a < kAxes; ++a) {
        step[a] *= 0.5;
        any_step_left = any_step_left || (step[a] >= min_step[a] && limit[a] > 0.0);
      }
    }
  }
  for (int a = 0; a < kAxes; ++a) {
    if (limit[a] > 0.0 &&
        std::abs(coord(out.pose, a) - coord(start_copy, a)) > limit[a] - min_step[a]) {
      out.hit_limit = true;
    }
  }
  return out;
}

PointList thinEvenly(const PointList& points, size_t max_points) {
  if (points.size() <= max_points) return points;
  PointList out;
  out.reserve(max_points);
  const double stride = static_cast<double>(points.size()) / max_points;
  for (size_t i = 0; i < max_points; ++i) out.push_back(points[static_cast<size_t>(i * stride)]);
  return out;
}

HillClimbOutcome hillClimb(const ExactScorer& scorer, const PointList& base_points,
                           const Pose6& start, const HillClimbOptions& o, TaskPool* pool) {
  // Per point set: the cells read at the pose the climb stands on, and at the pose scored last.
  struct Memo {
    std::vector<CellBlockMemo> kept, last;
  } full_memo, coarse_memo;
  ClimbObjective f;
  f.full = [&](const Pose6& p) {
    return scorer.scoreReusing(base_points, p, &full_memo.kept, &full_memo.last, pool);
  };
  f.full_kept = [&] { full_memo.kept.swap(full_memo.last); };
  PointList coarse;
  if (o.coarse_points > 0 && base_points.size() >= 2 * o.coarse_points) {
    coarse = thinEvenly(base_points, o.coarse_points);
    f.coarse = [&](const Pose6& p) {
      return scorer.scoreReusing(coarse, p, &coarse_memo.kept, &coarse_memo.last, pool);
    };
    f.coarse_kept = [&] { coarse_memo.kept.swap(coarse_memo.last); };
  }
  return hillClimb(f, start, o);
}

HillClimbOutcome hillClimb(const ClimbObjective& f, const Pose6& start, const HillClimbOptions& o) {
  if (!f.coarse) return climb(f.full, f.full_kept, start, start, o);
  HillClimbOptions first = o;
  first.min_xy_step_m *= 4.0;
  first.min_z_step_m *= 4.0;
  first.min_angle_step_rad *= 4.0;
  const HillClimbOutcome c = climb(f.coarse, f.coarse_kept, start, start, first);
  HillClimbOptions second = o;
  second.initial_xy_step_m = std::min(o.initial_xy_step_m, 2.0 * first.min_xy_step_m);
  second.initial_z_step_m = std::min(o.initial_z_step_m, 2.0 * first.min_z_step_m);
  second.initial_angle_step_rad =
      std::min(o.initial_angle_step_rad, 2.0 * first.min_angle_step_rad);
  second.max_evaluations = std::max(1, o.max_evaluations - c.evaluations);
  HillClimbOutcome out = climb(f.full, f.full_kept, c.pose, start, second);
  out.evaluations += c.evaluations;
  // The coarse climb's pose could score below the start on all points: never return worse.
  out.score_start = f.full(start);
  ++out.evaluations;
  if (out.score_start > out.score) {
    out.pose = start;
    out.score = out.score_start;
  }
  return out;
}

}  // namespace gmm_localization
