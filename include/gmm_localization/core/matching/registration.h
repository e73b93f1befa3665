#pragma once
// Full registration, paper Algorithm 1: filter and level the scan, align its height to the map,
// search x, y, heading exhaustively-optimally by branch-and-bound over the rasterized
// multiresolution map, hill-climb 6-DOF on the exact likelihood, estimate the covariance from
// the explored space, certify the optimum (match_certificate.h), and label obstacles.

#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/matching/fused_channel.h"
#include "gmm_localization/core/matching/global_certificate.h"
#include "gmm_localization/core/matching/global_search.h"
#include "gmm_localization/core/matching/grid_search.h"
#include "gmm_localization/core/matching/hill_climb.h"
#include "gmm_localization/core/matching/match_certificate.h"
#include "gmm_localization/core/matching/match_covariance.h"
#include "gmm_localization/core/matching/obstacle_classifier.h"
#include "gmm_localization/core/matching/scan_filter.h"

namespace gmm_localization {

struct RegistrationOptions {
  ScanFilterOptions filter;           ///< scan preparation for the search
  size_t refine_max_points = 3000;    ///< points the hill climb scores (evenly thinned); the
                                      ///< matcher config uses 1500 (faster, 2 mm coarser)
  double heading_step_rad = 0.00873;  ///< search heading resolution [rad] (0.5 deg)
  double z_search_m = 1.0;  ///< height pre-alignment range +- around the prior [m]; 0: off
  bool exhaustive = false;  ///< Algorithm 2 instead of branch-and-bound (reference, slow)
  BranchAndBoundOptions branch_and_bound;
  /// Windows with at least this many headings (121: wider than +-30 deg at the 0.5 deg step,
  /// e.g. a full turn for global localization) are searched by branch-and-bound over heading
  /// intervals (global_search.h), the others by branchAndBoundSearch. Same optimum either way.
  int interval_search_min_headings = 121;
  GlobalSearchOptions global;  ///< the interval search's options (its node budget included)
  HillClimbOptions hill_climb;
  CovarianceOptions covariance;
  CertificateOptions certificate;  ///< what the search proves about the rest of its window
  bool classify_obstacles = true;
  ObstacleOptions obstacles;
  /// A match is rejected when less than this share of the search points lies over non-empty
  /// map cells at the result (the scan is mostly off the map).
  double min_map_coverage = 0.2;
  /// Threads a match runs on, the caller's included (core/common/task_pool.h): the per-heading
  /// rotation, the search's and the covariance's headings, the refinement's and the labels'
  /// points, the certificate's next node in parallel (the scan filter stays on one thread); 0:
  /// one per hardware thread. Pays only when the match has the cores to itself (benchmarks.md).
  /// The result is bit-identical for any count (the work is cut into pieces that do not depend
  /// on it); only the search statistics may differ.
  int threads = 1;

  std::string validate() const;
};

struct MatchRequest {
  Pose6 prior;             ///< initial guess of base_link in the map frame
  double half_x_m = 12.5;  ///< search window half extents [m]
  double half_y_m = 12.5;
  double half_heading_rad = 0.26;  ///< [rad]
  /// Evaluation only: a pose (the ground truth) whose search score is reported as
  /// MatchResult::reference_deficit_per_point, to calibrate the certificate's margin.
  bool has_reference = false;
  Pose6 reference;
  /// The fused method (fused_channel.h): the scan's ground returns and the reflectivity map,
  /// searched and refined together with the height points (null: the height points alone).
  /// Owned by the caller for the duration of the call.
  const FusedChannel* fused = nullptr;
  /// A global (heading-interval) search, and the proof of its certificate after it, stop when
  /// another thread sets this flag: the answer is no longer wanted (kCancelled). Owned by the
  /// caller for the duration of the call.
  const std::atomic<bool>* cancel = nullptr;
};

struct MatchResult {
  Pose6 pose;                      ///< registered base_link pose in the map frame
  Eigen::Matrix3d covariance_xyh;  ///< x [m], y [m], yaw [rad]
  SearchOutcome search;            ///< discrete optimum and search statistics
  HillClimbOutcome refinement;
  MatchCovariance covariance_detail;
  MatchCertificate certificate;  ///< separation and protection level of the search optimum
  /// Protection level of the published pose: the certificate's (grid poses around the
  /// optimum) plus a cell's diagonal (a true pose lies within one cell of a plausible grid
  /// pose: the calibration scores the grid poses around the truth) and the refinement's shift
  /// from the optimum, x-y [m]; heading: plus a heading step and the shift [rad].
  double protection_xy_m = 0.0;
  double protection_heading_rad = 0.0;
  /// Optimum's score minus the best score of the grid poses around MatchRequest::reference
  /// (two per axis and heading) [nats per scan point]; NaN without a reference or when it
  /// lies outside the window.
  double reference_deficit_per_point = std::numeric_limits<double>::quiet_NaN();
  FilteredScan filtered;                  ///< counters and the search points
  double z_offset_m = 0.0;                ///< height pre-alignment applied to the prior [m]
  double map_coverage = 0.0;              ///< share of search points over non-empty cells
  double log_likelihood_per_point = 0.0;  ///< exact, at the result [nats]
  ObstacleLabels obstacles;               ///< one label per input point (when enabled)
  /// After a global search (windows of interval_search_min_headings headings or more):
  /// `search` is the global optimum (its evaluations include the confirming search's);
  /// `confirm_search` the search of GlobalSearchOptions::confirm_half_* around it on all points,
  /// from which the pose, the covariance and the protection level come; `global_certificate`
  /// the proof over the whole window (global_certificate.h). `certificate` is then certified
  /// only when both proofs are (its failure the global one's first), with the confirming
  /// search's separation.
  bool global = false;
  SearchOutcome confirm_search;
  MatchCertificate global_certificate;
};

/// Stage durations [s], filled when the caller supplies a clock (the core reads none itself).
struct RegistrationTiming {
  double filter_s = 0;  ///< filtering, height pre-alignment, per-heading rotation
  double search_s = 0, refine_s = 0, covariance_s = 0, certificate_s = 0, obstacles_s = 0;
};

/// The first stage of a match: the filtered scan, its height pre-alignment and the search
/// problem (rotated, discretised points) over the request's window.
struct PreparedSearch {
  FilteredScan filtered;
  double z_offset_m = 0.0;
  SearchProblem problem;
  FilteredScan ground;  ///< the fused method's filtered ground returns (else empty)
};

/// Why a registration produced no pose. Callers decide on the kind, never on the message text
/// (the messages are for people and may change).
enum class RegistrationError {
  kNone,            ///< no failure (the result holds a pose)
  kInvalidOptions,  ///< RegistrationOptions::validate() failed
  kInvalidPrior,    ///< the request's prior pose is not finite
  kNoPoints,        ///< no points left after filtering: nothing to search with
  kInvalidWindow,   ///< the request's search window is invalid (SearchWindow::validate)
  kOffMap,          ///< no rasterized map chunk under the scan anywhere in the search window
  kLowCoverage,     ///< too little of the scan over mapped cells at the best pose
  kNumerical,       ///< non-finite pose or covariance
  kSearchBudget,    ///< the interval search reached GlobalSearchOptions::max_evaluations
  kCancelled,       ///< the interval search or its certificate was stopped by MatchRequest::cancel
  kBelowFloor,      ///< no pose of the interval search's window reaches its score floor
                    ///< (GlobalSearchOptions::min_score_per_point): the vehicle is not there
};
const char* registrationErrorName(RegistrationError kind);  ///< "no_points", "off_map", ...

/// A Result<T> (value or reason) that also carries the failure's kind. It converts to Result<T>
/// (the kind is then dropped), so callers that only need the reason keep using Result<T>.
template <typename T>
class RegistrationResult : public Result<T> {
 public:
  RegistrationResult(T value) : Result<T>(std::move(value)) {}  // NOLINT: implicit on purpose
  static RegistrationResult failure(RegistrationError kind, std::string reason) {
    return RegistrationResult(Result<T>::failure(std::move(reason)), kind);
  }
  /// kNone when ok(); otherwise never kNone.
  RegistrationError errorKind() const { return kind_; }

 private:
  RegistrationResult(Result<T> base, RegistrationError kind)
      : Result<T>(std::move(base)), kind_(kind) {}
  RegistrationError kind_ = RegistrationError::kNone;
};

class Registration {
 public:
  /// Runs on `pool` when given (shared by several registrations), otherwise on a pool of its own
  /// of options.threads threads (none for 1); the global search and its certificate likewise on
  /// `global_pool`, else on a pool of options.global.threads (the same as `pool` when the
  /// counts agree).
  explicit Registration(const RegistrationOptions& options,
                        std::shared_ptr<TaskPool> pool = nullptr,
                        std::shared_ptr<TaskPool> global_pool = nullptr);
  const RegistrationOptions& options() const { return options_; }
  /// The pool the match runs on; null when it runs on the caller's thread alone.
  const std::shared_ptr<TaskPool>& pool() const { return pool_; }
  /// The pool of the global search and its certificate; null: the caller's thread alone.
  const std::shared_ptr<TaskPool>& globalPool() const { return global_pool_; }

  /// Registers `base_points` (base_link frame [m]) against `map`. Fails with a reason and its
  /// kind, never with a pose, for: invalid options or request, no points after filtering, scan
  /// off the loaded map, too little map coverage at the result, or a non-finite result.
  /// `traversal` receives the branch-and-bound's scored nodes (Fig. 9); `now` (seconds, any
  /// epoch) enables `timing`.
  RegistrationResult<MatchResult> match(const ChunkMap& map, const PointList& base_points,
                                        const MatchRequest& request,
                                        std::vector<TraversalNode>* traversal = nullptr,
                                        const std::function<double()>& now = nullptr,
                                        RegistrationTiming* timing = nullptr) const;

  /// A window of this many headings or more is searched over heading intervals (the global
  /// search, finished by finishGlobal()).
  bool searchesGlobally(const SearchWindow& window) const {
    return window.sizeH() >= options_.interval_search_min_headings;
  }

  /// The stages of match(), for tools that time or compare them (the benchmark runs both
  /// searches on one prepared problem). Same failures as match().
  RegistrationResult<PreparedSearch> prepare(const ChunkMap& map, const PointList& base_points,
                                             const MatchRequest& request) const;
  /// The search stage of match(): exhaustive (options().exhaustive), over heading intervals
  /// (windows of interval_search_min_headings headings or more) or branchAndBoundSearch.
  /// `complete` is false only when the interval search stopped at its node budget or at
  /// `cancel` (then `cancelled` is true), or proved that nothing reaches its score floor (then
  /// `below_floor` is true).
  SearchOutcome search(const SearchProblem& problem, std::vector<TraversalNode>* traversal,
                       bool* complete = nullptr, const std::atomic<bool>* cancel = nullptr,
                       bool* cancelled = nullptr, bool* below_floor = nullptr) const;
  /// Refinement, covariance, certificate, coverage check and obstacles after a search of
  /// `prepared`; after a global search, first its certificate and the confirming search
  /// (MatchResult::global).
  /// `search` is taken by value: moved in, what it kept for the certificates is freed once they
  /// are proved, without a copy.
  RegistrationResult<MatchResult> finish(const ChunkMap& map, const PointList& base_points,
                                         const MatchRequest& request, PreparedSearch prepared,
                                         SearchOutcome search, const std::function<double()>& now,
                                         RegistrationTiming* timing) const;

 private:
  RegistrationResult<MatchResult> finishLocal(const ChunkMap& map, const PointList& base_points,
                                              const MatchRequest& request, PreparedSearch prepared,
                                              SearchOutcome search,
                                              const std::function<double()>& now,
                                              RegistrationTiming* timing) const;
  RegistrationResult<MatchResult> finishGlobal(const ChunkMap& map, const PointList& base_points,
                                               const MatchRequest& request, PreparedSearch prepared,
                                               SearchOutcome search,
                                               const std::function<double()>& now,
                                               RegistrationTiming* timing) const;

  RegistrationOptions options_;
  std::shared_ptr<TaskPool> pool_;
  std::shared_ptr<TaskPool> global_pool_;
};

/// Height offset [m] (a multiple of the z step within +-range_m) that maximises the base-layer
/// score of the levelled points at `prior`; 0 when nothing scores.
double bestHeightOffset(const ChunkMap& map, const PointList& levelled_points, const Pose6& prior,
                        double range_m);

}  // namespace gmm_localization
