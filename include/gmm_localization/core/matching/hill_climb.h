#pragma once
// Paper Algorithm 1, line 2: a constrained 6-DOF hill climb on the exact likelihood, from the
// search's discrete optimum, for sub-cell x, y and heading and for z, roll and pitch.

#include <cstddef>
#include <functional>
#include <string>

#include "gmm_localization/core/matching/exact_scorer.h"

namespace gmm_localization {

struct HillClimbOptions {
  /// Largest change from the start in x and y [m], in heading [rad], in z [m] and in roll and
  /// pitch [rad]: the search's cell and heading step leave the optimum within about one step;
  /// z, roll and pitch start from the prior.
  double max_xy_m = 0.3;
  double max_yaw_rad = 0.012;
  double max_z_m = 0.5;
  double max_roll_pitch_rad = 0.035;
  /// First and smallest pattern steps [m] and [rad]: steps halve when no move improves.
  double initial_xy_step_m = 0.08;
  double initial_z_step_m = 0.04;
  double initial_angle_step_rad = 0.003;
  double min_xy_step_m = 0.005;
  double min_z_step_m = 0.005;
  double min_angle_step_rad = 0.0002;
  int max_evaluations = 400;
  /// Coarse-to-fine: climb first on this many evenly spaced points down to 4x the smallest
  /// steps, then on all points from there (about half the point evaluations of a single climb
  /// on all points, same optimum in practice). 0, or fewer than twice this many points: one
  /// climb on all points.
  size_t coarse_points = 750;

  std::string validate() const;
};

struct HillClimbOutcome {
  Pose6 pose;
  double score_start = 0.0;  ///< exact log-likelihood at the start [nats]
  double score = 0.0;        ///< at the result [nats]
  int evaluations = 0;       ///< poses tried, the start included (the budget counts these)
  int repeated = 0;          ///< ... of them a pose the same climb had scored: passed over unscored
  bool hit_limit = false;    ///< some coordinate ended on its constraint
};

/// The pose objective of a climb [nats]: `full` on all points; `coarse` on the thinned ones of
/// the coarse-to-fine stage (HillClimbOptions::coarse_points), empty: one climb with `full`.
struct ClimbObjective {
  std::function<double(const Pose6&)> full;
  std::function<double(const Pose6&)> coarse;
  /// Optional: called right after a score of `full` (`coarse`) whose pose the climb moved to,
  /// the start included. The next poses scored differ from that one in one coordinate: an
  /// objective may keep what it computed there to reuse (ExactScorer::scoreReusing).
  std::function<void()> full_kept, coarse_kept;
};

/// Every (size / max_points)-th point, `max_points` of them; all when there are no more.
PointList thinEvenly(const PointList& points, size_t max_points);

/// The coordinate pattern search of hillClimb below on any objective.
HillClimbOutcome hillClimb(const ClimbObjective& objective, const Pose6& start,
                           const HillClimbOptions& options);

/// Coordinate pattern search over (x, y, z, roll, pitch, yaw) maximising scorer.score(points,
/// pose) within the box around `start`, coarse-to-fine (options.coarse_points). Deterministic;
/// never returns a worse pose than start (scored on all points). `pool`: each score's point
/// blocks in parallel (the same result, bit for bit). The poses are scored by
/// ExactScorer::scoreReusing, each reusing the cells of the pose the climb stands on and of its
/// last trial one step the same way (same path, pose and score as scoring every pose afresh).
HillClimbOutcome hillClimb(const ExactScorer& scorer, const PointList& base_points,
                           const Pose6& start, const HillClimbOptions& options,
                           TaskPool* pool = nullptr);

}  // namespace gmm_localization
