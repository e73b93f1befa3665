#pragma once
// Whether the matcher ever got its first match from the pose it was given: counts the scans
// searched around one explicit pose (the configured initial pose, an /initialpose, a pose
// recalled from the match history: Prior::explicit_generation) and rejected, with none accepted,
// and says when the console line "give a better pose" is due. A pose farther from the vehicle
// than every window searched around it (its own window, then the global one once the
// localization is lost, RelocalizationPolicyOptions::lost_after_rejections) is rejected forever
// otherwise without a word. ROS-free; the caller passes the time and locks.

#include <cstdint>

#include "gmm_localization/core/localization/match_processor.h"

namespace gmm_localization {

struct AcquisitionWatchOptions {
  /// Rejected scans around one explicit pose, none accepted, after which the pose is stuck.
  int warn_after_rejections = 5;
  /// The console line repeats this often while stuck [s].
  double repeat_s = 15.0;
};

/// The rejection count at which a pose counts as stuck for these relocalization options:
/// max_consecutive_rejections, when a tracking matcher would relocalize. Early on purpose: a
/// wide search takes seconds, and the global one (lost_after_rejections later) may never reach
/// the vehicle; the line says which of the two stages the matcher is in.
int acquisitionWarnAfter(const RelocalizationPolicyOptions& relocalization);

class AcquisitionWatch {
 public:
  explicit AcquisitionWatch(const AcquisitionWatchOptions& options = AcquisitionWatchOptions())
      : options_(options) {}

  /// One processed scan: the explicit_generation of its prior (0: not an explicit pose, e.g. the
  /// EKF posterior), its outcome and the half extent in x and y of the window it searched [m].
  /// Skipped scans (no map, no usable points) do not count.
  void onScan(uint64_t explicit_generation, MatchOutcome outcome, double window_half_xy_m);

  /// An explicit pose has been rejected warn_after_rejections times, none accepted.
  bool stuck() const;
  int rejections() const { return rejections_; }
  /// Widest window searched around the current pose [m] (half extent).
  double widestWindowM() const { return widest_m_; }
  /// stuck(), and its line has not been given yet or was given repeat_s ago. Marks it given.
  bool due(double now_s);

 private:
  AcquisitionWatchOptions options_;
  uint64_t generation_ = 0;  ///< the explicit pose counted (0: none)
  int rejections_ = 0;
  double widest_m_ = 0.0;
  bool reported_ = false;
  double reported_s_ = 0.0;
};

}  // namespace gmm_localization
