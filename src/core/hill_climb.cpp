#include "gmm_localization/core/hill_climb.h"

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

HillClimbOutcome hillClimb(const ExactScorer& scorer, const PointList& base_points,
                           const Pose6& start, const HillClimbOptions& o) {
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
  out.score_start = out.score = scorer.score(base_points, start);
  out.evaluations = 1;
  Pose6 start_copy = start;
  bool any_step_left = true;
  while (any_step_left && out.evaluations < o.max_evaluations) {
    bool improved = false;
    for (int a = 0; a < kAxes && out.evaluations < o.max_evaluations; ++a) {
      if (step[a] < min_step[a] || limit[a] <= 0.0) continue;
      const double origin = coord(start_copy, a);
      for (double sign : {+1.0, -1.0}) {
        Pose6 trial = out.pose;
        double& v = coord(trial, a);
        v += sign * step[a];
        if (std::abs(v - origin) > limit[a] + 1e-12) continue;
        const double s = scorer.score(base_points, trial);
        ++out.evaluations;
        if (s > out.score) {
          out.score = s;
          out.pose = trial;
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

}  // namespace gmm_localization
