#pragma once
// MatchProcessor: what the matcher does with one scan, ROS-free, shared by the matcher
// nodelet's worker thread and by LocalizerPipeline: deskew with the INS twist, size the window
// from the prior (match_policy.h), run Registration::match (paper Algorithm 1), apply
// the acceptance rules and compute the covariance to publish. Its MatchReport carries every
// field of gmm_localization/MatchStatus.
//
// Thread-safety: process() is const and may run concurrently on different inputs.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "gmm_localization/core/localization/prior_tracker.h"
#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {

/// A merged LIDAR revolution in base_link.
struct ScanInput {
  double stamp_s = 0.0;  ///< [s]
  PointList points;      ///< base_link [m]; non-finite points allowed (dropped and counted)
  /// Per-point capture time relative to stamp_s [s] (empty: no deskewing), same size as points.
  std::vector<float> time_s;
  /// Per-point intensity (empty: the cloud has none), same size as points; the reflectivity
  /// method needs it.
  std::vector<float> intensity;
  /// How time_s was read, for the status (e.g. "'t' uint32 relative nanoseconds"); empty: none.
  std::string time_source;
  /// Why time_s is empty although the cloud has a time field (its times make no sense).
  std::string time_problem;
  /// Evaluation only: the ground-truth pose, whose search score deficit the result reports
  /// (MatchResult::reference_deficit_per_point).
  bool has_reference = false;
  Pose6 reference;
};

/// How the scan ended, for the relocalization state machine.
enum class MatchOutcome {
  kAccepted,  ///< pose published
  kRejected,  ///< a search ran (or the scan fell off the map) but the result was not accepted
  kSkipped,   ///< nothing to search with: no prior, no map, no usable points
};
const char* matchOutcomeName(MatchOutcome outcome);  ///< "accepted", "rejected", "skipped"

struct MatchReport {
  double stamp_s = 0.0;
  MatchOutcome outcome = MatchOutcome::kSkipped;
  bool accepted() const { return outcome == MatchOutcome::kAccepted; }
  std::string reason;                 ///< why not accepted; empty when accepted
  bool likelihood_collapsed = false;  ///< rejected by the likelihood-collapse rule

  Prior prior;
  /// The matcher's prior mode once this scan's outcome was learnt (MatchSessionState::
  /// finishMatch): relocalizing or lost tell the filter its estimate is not confirmed.
  PriorMode mode_after = PriorMode::kNoPrior;
  WindowExtent window;         ///< requested half extents
  SearchWindow search_window;  ///< discretised (cells, heading steps), valid when searched
  /// The window is searched over heading intervals (the global search: at least the
  /// registration's interval_search_min_headings headings), whatever the outcome.
  bool global_window = false;
  bool deskewed = false;
  std::string time_source;  ///< ScanInput::time_source
  /// Why the scan was not deskewed (no or refused per-point times, no twist, skipped before);
  /// empty when deskewed.
  std::string deskew_note;

  // Input
  size_t input_points = 0;
  size_t dropped_nonfinite = 0;
  size_t search_points = 0;
  // Search and result (valid when a registration returned a result)
  bool has_result = false;
  MatchResult result;            ///< registration output (pose, search, obstacles, filtered scan)
  double correction_xy_m = 0.0;  ///< distance from the prior to the result [m]
  double correction_yaw_rad = 0.0;
  Pose6 pose;                              ///< published pose (when accepted)
  Matrix6d covariance = Matrix6d::Zero();  ///< published covariance (when accepted)
  // Timing [s] (when a clock was given)
  RegistrationTiming timing;
  double total_s = 0.0;

  /// The scan as registered (deskewed, base_link): the points `result.obstacles` labels.
  PointList points;
  /// Branch-and-bound traversal (when requested and searched).
  std::vector<TraversalNode> traversal;
};

/// What the scans are matched against: the paper's height layer (the default), the
/// reflectivity baseline (core/map/reflectivity_layer.h; the map must hold that layer), or both
/// likelihoods summed (core/matching/fused_channel.h; the height map plus its reflectivity
/// layer).
enum class MatchMethod { kHeight, kReflectivity, kFused };
const char* matchMethodName(MatchMethod method);  ///< "height", "reflectivity", "fused"
/// The method named `name`; false (out untouched) for an unknown name.
bool parseMatchMethod(const std::string& name, MatchMethod* out);

struct MatchMethodOptions {
  MatchMethod method = MatchMethod::kHeight;
  ReflectivityLayerOptions reflectivity;
  /// The ground returns' intensity is needed (reflectivity and fused).
  bool needsIntensity() const { return method != MatchMethod::kHeight; }
  std::string validate() const;
};

class MatchProcessor {
 public:
  /// Validates the option sets; the reason names the offending key.
  /// `defer_obstacles`: process() leaves the obstacle labels (paper V-C, RegistrationOptions::
  /// classify_obstacles) to labelObstacles(), so that a caller can publish the pose first.
  static Result<MatchProcessor> create(const RegistrationOptions& registration,
                                       const LocalizationPolicyOptions& policy,
                                       const MatchMethodOptions& method = {},
                                       bool defer_obstacles = false);

  /// Processes one scan (moved in, deskewed in place, returned in the report's `points`). `twist`:
  /// the body twist for deskewing (null: no deskewing). `want_traversal`: record the search
  /// traversal. `now` (seconds, any epoch) enables the timings. Never throws; every failure is a
  /// report with a reason. An accepted report always has a finite pose and covariance.
  /// `reflectivity_map`: the fused method's second map (its reflectivity layer, rasterized like
  /// `map`); without it a fused scan is skipped with the reason. `cancel`: a global search
  /// stops when another thread sets it (MatchRequest::cancel; the scan is then rejected with
  /// the reason).
  MatchReport process(const ChunkMap& map, ScanInput scan, const Prior& prior,
                      const BodyTwist* twist, bool want_traversal,
                      const std::function<double()>& now = nullptr,
                      const ChunkMap* reflectivity_map = nullptr,
                      const std::atomic<bool>* cancel = nullptr) const;

  /// With defer_obstacles: labels the points of `report` at its registration's pose, as
  /// process() would have (the same labels and counts), and adds the time to its timing and
  /// total (when `now` is given). Nothing without a result, for the reflectivity method (which
  /// labels nothing), with classify_obstacles off or when process() labelled them already.
  void labelObstacles(const ChunkMap& map, MatchReport& report,
                      const std::function<double()>& now = nullptr) const;

  /// The options the scans are registered with (classify_obstacles as given to create(), also
  /// when the labels are deferred).
  const RegistrationOptions& registrationOptions() const { return options_; }
  const LocalizationPolicyOptions& policyOptions() const { return policy_; }
  const MatchMethodOptions& methodOptions() const { return method_; }

 private:
  MatchProcessor(const RegistrationOptions& options, const RegistrationOptions& tracking,
                 const RegistrationOptions& unknown_z, const RegistrationOptions& reflectivity,
                 const LocalizationPolicyOptions& policy, const MatchMethodOptions& method,
                 bool deferred_labels)
      : options_(options),
        tracking_(tracking),
        unknown_z_(unknown_z, tracking_.pool(), tracking_.globalPool()),
        reflectivity_(reflectivity, tracking_.pool(), tracking_.globalPool()),
        policy_(policy),
        method_(method),
        deferred_labels_(deferred_labels) {}

  RegistrationOptions options_;  ///< as given (the registrations' may leave the labels out)

  Registration tracking_;      ///< prior height known
  Registration unknown_z_;     ///< wider height pre-alignment (planar initial pose)
  Registration reflectivity_;  ///< the reflectivity layer (x, y, heading)
  LocalizationPolicyOptions policy_;
  MatchMethodOptions method_;
  bool deferred_labels_ = false;  ///< process() leaves the labels to labelObstacles()
};

}  // namespace gmm_localization
