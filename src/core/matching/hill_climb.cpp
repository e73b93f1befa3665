#include "gmm_localization/core/matching/hill_climb.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

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

namespace {
/// The poses a climb has scored, bit for bit. The climb stands on the best of them, and a move
/// needs a strictly higher score, so a trial that repeats one of them (the axes tried after the
/// last move of a sweep, tried again from the same pose in the next sweep) cannot move it: it
/// is passed over, not scored again, and the climb takes the same path.
class ScoredPoses {
 public:
  bool seen(const Pose6& p) const {
    const std::array<double, kAxes> c = coordinates(p);
    for (const std::array<double, kAxes>& q : poses_) {
      if (std::memcmp(q.data(), c.data(), sizeof(c)) == 0) return true;
    }
    return false;
  }
  void add(const Pose6& p) { poses_.push_back(coordinates(p)); }

 private:
  static std::array<double, kAxes> coordinates(const Pose6& p) {
    return {p.x, p.y, p.z, p.roll, p.pitch, p.yaw};
  }
  std::vector<std::array<double, kAxes>> poses_;
};
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
  ScoredPoses scored;
  scored.add(start);
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
        ++out.evaluations;
        if (scored.seen(trial)) {
          ++out.repeated;  // scored already, at most the score the climb then stood on: no move
          continue;
        }
        const double s = score(trial);
        scored.add(trial);
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

namespace {
/// The cells a climb on one point set read: at the pose it stands on, at the pose scored last,
/// and at the last trial one step along each axis and sign (a trial step in z, roll or pitch
/// changes every height, so the pose it stands on has none of its cells; the same trial after
/// steps in x, y or heading finds most of them there, heights unchanged and cells mostly too).
class ClimbMemo {
 public:
  ClimbMemo(const ExactScorer& scorer, const PointList& points, TaskPool* pool)
      : scorer_(scorer), points_(points), pool_(pool) {}

  double score(const Pose6& p) {
    last_pose_ = p;
    last_trial_ = trialOf(p);
    std::vector<CellBlockMemo>* same_way = last_trial_ >= 0 ? &trials_[last_trial_] : nullptr;
    const double s = scorer_.scoreReusing(points_, p, &kept_, &last_, pool_, same_way);
    if (same_way != nullptr) same_way->swap(last_);  // last_ keeps an older memo: any will do
    return s;
  }
  /// The climb moved to the pose scored last.
  void moved() {
    kept_.swap(last_trial_ >= 0 ? trials_[last_trial_] : last_);
    kept_pose_ = last_pose_;
    has_kept_ = true;
  }

 private:
  /// 2 * axis + (step down ? 1 : 0) when p differs from the kept pose in one coordinate, else -1.
  int trialOf(const Pose6& p) const {
    if (!has_kept_) return -1;
    const double d[6] = {p.x - kept_pose_.x,         p.y - kept_pose_.y,
                         p.z - kept_pose_.z,         p.roll - kept_pose_.roll,
                         p.pitch - kept_pose_.pitch, p.yaw - kept_pose_.yaw};
    int trial = -1;
    for (int a = 0; a < 6; ++a) {
      if (d[a] == 0.0) continue;
      if (trial >= 0) return -1;
      trial = 2 * a + (d[a] < 0.0 ? 1 : 0);
    }
    return trial;
  }

  const ExactScorer& scorer_;
  const PointList& points_;
  TaskPool* pool_;
  std::vector<CellBlockMemo> kept_, last_, trials_[12];
  Pose6 kept_pose_, last_pose_;
  bool has_kept_ = false;
  int last_trial_ = -1;
};
}  // namespace

HillClimbOutcome hillClimb(const ExactScorer& scorer, const PointList& base_points,
                           const Pose6& start, const HillClimbOptions& o, TaskPool* pool) {
  ClimbMemo full_memo(scorer, base_points, pool);
  ClimbObjective f;
  f.full = [&](const Pose6& p) { return full_memo.score(p); };
  f.full_kept = [&] { full_memo.moved(); };
  PointList coarse;
  if (o.coarse_points > 0 && base_points.size() >= 2 * o.coarse_points) {
    coarse = thinEvenly(base_points, o.coarse_points);
  }
  ClimbMemo coarse_memo(scorer, coarse, pool);
  if (!coarse.empty()) {
    f.coarse = [&](const Pose6& p) { return coarse_memo.score(p); };
    f.coarse_kept = [&] { coarse_memo.moved(); };
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
  out.repeated += c.repeated;
  // The coarse climb's pose could score below the start on all points: never return worse.
  // (When the coarse climb stayed on the start, the full climb began by scoring it.)
  if (std::memcmp(&c.pose, &start, sizeof(Pose6)) != 0) {
    out.score_start = f.full(start);
    ++out.evaluations;
  }
  if (out.score_start > out.score) {
    out.pose = start;
    out.score = out.score_start;
  }
  return out;
}

}  // namespace gmm_localization
