// The hill climb's pattern search (core/matching/hill_climb.h) against a reference that scores
// every trial, on a seeded synthetic objective: passing over the trials that repeat a pose
// already scored takes the same path to the same pose and score, bit for bit, and never asks the
// objective for the same pose twice.
#include "gmm_localization/core/matching/hill_climb.h"

#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

using Coordinates = std::array<double, 6>;

Coordinates coordinatesOf(const Pose6& p) { return {p.x, p.y, p.z, p.roll, p.pitch, p.yaw}; }

double& coordinate(Pose6& p, int a) {
  double* c[6] = {&p.x, &p.y, &p.z, &p.roll, &p.pitch, &p.yaw};
  return *c[a];
}

/// A peaked objective with ripples (local optima a pattern search can stop on) and coupled
/// axes, its peak at `peak`.
struct Ripples {
  Pose6 peak;
  double operator()(const Pose6& p) const {
    const double dx = p.x - peak.x, dy = p.y - peak.y, dz = p.z - peak.z;
    const double dr = p.roll - peak.roll, dp = p.pitch - peak.pitch, dh = p.yaw - peak.yaw;
    return -(dx * dx + 2.0 * dy * dy + 0.5 * dx * dy + 4.0 * dz * dz) -
           300.0 * (dr * dr + dp * dp) - 2000.0 * dh * dh - 0.3 * dh * dx +
           0.002 * std::sin(90.0 * p.x) * std::cos(70.0 * p.y);
  }
};

/// The pattern search of hill_climb.cpp as it was before repeated trials were passed over:
/// every trial scored; from `start`, within the box around `centre`.
HillClimbOutcome referenceClimb(const std::function<double(const Pose6&)>& score,
                                const Pose6& start, const Pose6& centre,
                                const HillClimbOptions& o) {
  const double limit[6] = {o.max_xy_m,           o.max_xy_m,           o.max_z_m,
                           o.max_roll_pitch_rad, o.max_roll_pitch_rad, o.max_yaw_rad};
  double step[6] = {o.initial_xy_step_m,      o.initial_xy_step_m,      o.initial_z_step_m,
                    o.initial_angle_step_rad, o.initial_angle_step_rad, o.initial_angle_step_rad};
  const double min_step[6] = {o.min_xy_step_m,      o.min_xy_step_m,      o.min_z_step_m,
                              o.min_angle_step_rad, o.min_angle_step_rad, o.min_angle_step_rad};
  HillClimbOutcome out;
  out.pose = start;
  out.score_start = out.score = score(start);
  out.evaluations = 1;
  bool any_step_left = true;
  while (any_step_left && out.evaluations < o.max_evaluations) {
    bool improved = false;
    for (int a = 0; a < 6 && out.evaluations < o.max_evaluations; ++a) {
      if (step[a] < min_step[a] || limit[a] <= 0.0) continue;
      for (double sign : {+1.0, -1.0}) {
        Pose6 trial = out.pose;
        Pose6 box = centre;
        double& v = coordinate(trial, a);
        v += sign * step[a];
        if (std::abs(v - coordinate(box, a)) > limit[a] + 1e-12) continue;
        const double s = score(trial);
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
      for (int a = 0; a < 6; ++a) {
        step[a] *= 0.5;
        any_step_left = any_step_left || (step[a] >= min_step[a] && limit[a] > 0.0);
      }
    }
  }
  return out;
}

/// An objective that records the poses it was asked for.
struct Recorded {
  Ripples f;
  std::vector<Coordinates> asked;
  double operator()(const Pose6& p) {
    asked.push_back(coordinatesOf(p));
    return f(p);
  }
  bool askedTwice() const {
    std::set<Coordinates> distinct(asked.begin(), asked.end());
    return distinct.size() != asked.size();
  }
};

class HillClimbTest : public testing::Test {
 protected:
  /// Seeded peaks and starts within the climb's box.
  static std::vector<std::pair<Ripples, Pose6>> cases() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<std::pair<Ripples, Pose6>> out;
    for (int c = 0; c < 40; ++c) {
      Pose6 start{100.0 * u(rng), 100.0 * u(rng), 0.5 * u(rng), 0.0, 0.0, 3.0 * u(rng)};
      Ripples f;
      f.peak = start;
      f.peak.x += 0.2 * u(rng);
      f.peak.y += 0.2 * u(rng);
      f.peak.z += 0.3 * u(rng);
      f.peak.roll += 0.02 * u(rng);
      f.peak.pitch += 0.02 * u(rng);
      f.peak.yaw += 0.01 * u(rng);
      out.emplace_back(f, start);
    }
    return out;
  }
};

TEST_F(HillClimbTest, PassingOverRepeatedTrialsTakesTheReferencePathAndNeverScoresAPoseTwice) {
  int repeated = 0;
  int c = 0;
  for (const auto& [f, start] : cases()) {
    HillClimbOptions o;
    Recorded recorded{f, {}};
    ClimbObjective objective;
    objective.full = [&](const Pose6& p) { return recorded(p); };
    const HillClimbOutcome got = hillClimb(objective, start, o);
    const HillClimbOutcome want = referenceClimb(f, start, start, o);
    EXPECT_EQ(std::memcmp(&got.pose, &want.pose, sizeof(Pose6)), 0) << "case " << c;
    EXPECT_EQ(got.score, want.score) << "case " << c;
    EXPECT_EQ(got.score_start, want.score_start) << "case " << c;
    EXPECT_EQ(got.evaluations, want.evaluations) << "case " << c;  // the same trials
    EXPECT_EQ(static_cast<int>(recorded.asked.size()) + got.repeated, got.evaluations)
        << "case " << c;
    EXPECT_FALSE(recorded.askedTwice()) << "case " << c;
    EXPECT_GT(want.score, want.score_start) << "case " << c;  // a climb, not a stop
    repeated += got.repeated;
    ++c;
  }
  EXPECT_GT(repeated, 0);  // repeated trials occur, so the comparison above tested something
}

TEST_F(HillClimbTest, CoarseToFineMatchesTheReferenceStages) {
  int c = 0;
  for (const auto& [f, start] : cases()) {
    HillClimbOptions o;
    Recorded coarse{f, {}}, full{f, {}};
    // The coarse objective differs from the full one (as fewer points would), so that the
    // stages can be told apart.
    auto coarse_f = [&f = f](const Pose6& p) { return f(p) + 0.001 * std::cos(40.0 * p.y); };
    ClimbObjective objective;
    objective.coarse = [&](const Pose6& p) {
      coarse(p);
      return coarse_f(p);
    };
    objective.full = [&](const Pose6& p) { return full(p); };
    const HillClimbOutcome got = hillClimb(objective, start, o);
    // The reference stages as hillClimb documents them.
    HillClimbOptions first = o;
    first.min_xy_step_m *= 4.0;
    first.min_z_step_m *= 4.0;
    first.min_angle_step_rad *= 4.0;
    const HillClimbOutcome c1 = referenceClimb(coarse_f, start, start, first);
    HillClimbOptions second = o;
    second.initial_xy_step_m = std::min(o.initial_xy_step_m, 2.0 * first.min_xy_step_m);
    second.initial_z_step_m = std::min(o.initial_z_step_m, 2.0 * first.min_z_step_m);
    second.initial_angle_step_rad =
        std::min(o.initial_angle_step_rad, 2.0 * first.min_angle_step_rad);
    second.max_evaluations = std::max(1, o.max_evaluations - c1.evaluations);
    HillClimbOutcome c2 = referenceClimb(f, c1.pose, start, second);
    const double at_start = f(start);
    if (at_start > c2.score) {
      c2.pose = start;
      c2.score = at_start;
    }
    EXPECT_EQ(std::memcmp(&got.pose, &c2.pose, sizeof(Pose6)), 0) << "case " << c;
    EXPECT_EQ(got.score, c2.score) << "case " << c;
    EXPECT_EQ(got.score_start, at_start) << "case " << c;
    EXPECT_FALSE(coarse.askedTwice()) << "case " << c;
    if (std::memcmp(&c1.pose, &start, sizeof(Pose6)) == 0) {
      EXPECT_FALSE(full.askedTwice()) << "case " << c;  // the start scored once, not again
    }
    ++c;
  }
}

}  // namespace
}  // namespace gmm_localization
