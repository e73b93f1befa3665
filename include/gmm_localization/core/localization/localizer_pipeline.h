#pragma once
// LocalizerPipeline: the matcher and ekf nodelets' logic without ROS, for the offline
// `evaluate` tool and for tests. It composes the same classes the nodelets use -
// LocalizationFilter (the ekf nodelet), MatchSession + MatchProcessor (the matcher nodelet;
// the session owns the PriorTracker and the OdometryBuffer) - and reproduces the nodelets'
// timing on a virtual clock:
//
// - Inputs are given in time order (IMU, INS odometry, scans; a bag's order). The virtual time
//   is the stamp of the newest input (a scan "arrives" at stamp + scan_arrival_delay_s).
// - One matcher worker and the nodelet's scan queue (MatchSession, session.scan_queue_size,
//   3 as shipped): a scan that arrives while the worker is idle starts at once; one that
//   arrives while it is busy waits in the queue, in arrival order; a scan arriving at a full
//   queue drops the oldest waiting one (counted in the next report), exactly as the nodelet's
//   worker. When a match finishes, the oldest waiting scan starts. A scan whose prior is lost
//   goes to the global worker when it is idle (the nodelet's second thread), and the worker
//   takes the next scan at once; while the global search runs, lost priors are interim ones
//   (MatchSessionState::beginMatch). Matches complete in the order they finish.
// - A match started at time t_start uses the EKF posterior at t_start (what the ekf nodelet
//   last published) carried by odometry to the scan stamp; its result becomes available at
//   t_start + processing_latency_s, when it is fused into the filter as a delayed measurement
//   (the filter re-fuses the IMU and odometry received since its stamp), and the prior tracker
//   learns the outcome (MatchSession::finishMatch).
// - Scan stamps going backwards by more than session.time_backwards_tolerance_s reset the
//   matcher session (the filter resets itself on its own inputs), re-arming the configured
//   pose; the waiting scans are dropped and a running match is completed at once and discarded
//   by the session's epoch check, as the nodelet discards it when it finishes.
//
// Deterministic for a given input sequence when every latency is given (>= 0); a negative
// latency uses the measured processing time (needs `clock`).

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gmm_localization/core/localization/localization_filter.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/localization/match_session.h"

namespace gmm_localization {

struct LocalizerPipelineOptions {
  EkfOptions ekf;
  FilterPolicyOptions filter;
  RegistrationOptions registration;
  LocalizationPolicyOptions policy;
  MatchMethodOptions method;          ///< what is matched (height, reflectivity or fused)
  MatchSessionOptions session;        ///< the matcher nodelet's session (and scan queue)
  double scan_arrival_delay_s = 0.0;  ///< scan available at stamp + this [s]
  /// >= 0: a global search (a lost prior, run by the global worker) takes this long instead of
  /// its scan's latency [s]; the global search takes seconds where a tracking match takes
  /// tens of milliseconds.
  double global_search_latency_s = -1.0;
  /// A global search takes its own measured time (MatchReport::total_s; needs `clock`), as it
  /// does on the vehicle, instead of a fixed one; overrides global_search_latency_s.
  bool global_search_latency_measured = false;
  bool record_traversal = false;  ///< keep each search's traversal in its report
  /// Optional clock [s] for the timings and for measured latencies (negative latency).
  std::function<double()> clock;

  std::string validate() const;
};

/// One scan's life through the pipeline.
struct PipelineScanReport {
  MatchReport match;
  double arrival_s = 0.0;          ///< virtual time the scan arrived
  double start_s = 0.0;            ///< matching started
  double finish_s = 0.0;           ///< result available (and fused)
  uint32_t dropped_before = 0;     ///< stale scans dropped since the previous report
  bool offered_to_filter = false;  ///< accepted and given to the filter
  FuseReport fuse;                 ///< the filter's outcome, when offered
};

class LocalizerPipeline {
 public:
  static Result<LocalizerPipeline> create(const LocalizerPipelineOptions& options);

  /// The rasterized map to search (shared, immutable while the pipeline holds it).
  void setMap(std::shared_ptr<const ChunkMap> map) { map_ = std::move(map); }
  /// The fused method's second map: the reflectivity layer, rasterized like setMap's.
  void setReflectivityMap(std::shared_ptr<const ChunkMap> map) {
    reflectivity_map_ = std::move(map);
  }
  /// Like the matcher's configured initial pose: searched with the wide window at the next
  /// scan (not carried by odometry), and again after each reset when
  /// session.configured_pose_on_reset.
  /// window: its own search window (null: the policy's wide window).
  void setConfiguredPose(const Pose6& pose, bool z_known, const WindowExtent* window = nullptr);
  /// Like /initialpose received by both nodelets at stamp_s: the filter is (re)started there
  /// and the matcher searches the wide window around it. z_known false: z, roll and pitch
  /// are completed from the posterior (planar pose).
  Status setInitialPose(const Pose6& pose, const Matrix6d& covariance, double stamp_s,
                        bool z_known);
  /// Like the ekf nodelet's relocalize service.
  Status relocalize(double stamp_s);

  /// Inputs, in time order.
  void addImu(const ImuMeasurement& imu);
  /// INS odometry: the pose feeds the odometry buffer, the twist the filter.
  void addOdometry(const OdometrySample& sample, const TwistMeasurement& twist);
  /// A GNSS fix (the filter's optional GNSS input, placed with setGeoreference's georeference).
  FuseReport addGnss(const GnssFix& fix);
  void setGeoreference(const Georeference& georeference) { filter_.setGeoreference(georeference); }
  /// A merged scan in base_link; processing_latency_s: how long its match takes [s] (< 0:
  /// measured with options.clock).
  void addScan(ScanInput scan, double processing_latency_s);
  /// Completes the running and the waiting scans (end of input).
  void flush();

  /// Reports of the scans completed since the last call, in completion order.
  std::vector<PipelineScanReport> takeReports();
  /// The filter's state at time_s (fails when the filter is not running).
  Result<EkfState> stateAt(double time_s) const { return filter_.stateAt(time_s); }
  const LocalizationFilter& filter() const { return filter_; }
  const MatchSessionState& session() const { return session_; }
  const PriorTracker& tracker() const { return session_.tracker(); }
  const OdometryBuffer& odometry() const { return session_.odometry(); }
  const LocalizerPipelineOptions& options() const { return options_; }
  uint64_t droppedScans() const { return session_.droppedTotal(); }
  uint64_t resets() const { return session_.resets(); }

 private:
  LocalizerPipeline(const LocalizerPipelineOptions& options, LocalizationFilter filter,
                    MatchProcessor processor);
  /// A scan waiting for the worker.
  struct WaitingScan {
    ScanInput scan;
    double arrival_s = 0.0;
    double latency_s = 0.0;
  };
  /// A running match: its report and the session epoch it began in.
  struct InFlight {
    PipelineScanReport report;
    uint64_t epoch = 0;
  };

  void advanceTo(double t);
  /// Completes the running match that finishes first (the worker's or the global worker's);
  /// then, when the worker is free, the oldest waiting scan starts (unless it was discarded by
  /// a reset).
  void completeFirst();
  /// Starts the oldest waiting scan, not before `now` nor before it arrived; a global search
  /// goes to the global worker and the next scan starts too.
  void startNext(double now);
  bool anyInFlight() const { return in_flight_.has_value() || global_in_flight_.has_value(); }

  LocalizerPipelineOptions options_;
  LocalizationFilter filter_;
  MatchProcessor processor_;
  MatchSession<WaitingScan> session_;
  std::shared_ptr<const ChunkMap> map_;
  std::shared_ptr<const ChunkMap> reflectivity_map_;  ///< the fused method's (else null)

  std::optional<InFlight> in_flight_;         ///< the worker's match
  std::optional<InFlight> global_in_flight_;  ///< the global worker's
  std::vector<PipelineScanReport> reports_;
};

/// The posterior the ekf nodelet publishes, from a filter state.
PosteriorEstimate posteriorFromState(const EkfState& state);

}  // namespace gmm_localization
