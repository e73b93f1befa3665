#pragma once
// LocalizerPipeline: the matcher and ekf nodelets' logic without ROS, for the offline
// `evaluate` tool and for tests. It composes the same classes the nodelets use -
// LocalizationFilter (the ekf nodelet), PriorTracker + MatchProcessor (the matcher nodelet) and
// an OdometryBuffer - and reproduces the nodelets' timing on a virtual clock:
//
// - Inputs are given in time order (IMU, INS odometry, scans; a bag's order). The virtual time
//   is the stamp of the newest input (a scan "arrives" at stamp + scan_arrival_delay_s).
// - One matcher worker: a scan that arrives while the worker is idle starts at once; one that
//   arrives while it is busy waits in a single slot, and a newer scan replaces it (the older
//   is dropped and counted in the next report), exactly as the nodelet's worker.
// - A match started at time t_start uses the EKF posterior at t_start (what the ekf nodelet
//   last published) carried by odometry to the scan stamp; its result becomes available at
//   t_start + processing_latency_s, when it is fused into the filter as a delayed measurement
//   (the filter re-fuses the IMU and odometry received since its stamp), and the prior tracker
//   learns the outcome.
// - Scan stamps going backwards by more than time_backwards_tolerance_s reset the matcher
//   state (the filter resets itself on its own inputs), re-arming the configured pose.
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

namespace gmm_localization {

struct LocalizerPipelineOptions {
  EkfOptions ekf;
  FilterPolicyOptions filter;
  RegistrationOptions registration;
  LocalizationPolicyOptions policy;
  double odometry_buffer_s = 10.0;            ///< INS history kept [s]
  double odometry_max_extrapolation_s = 0.3;  ///< [s] past the newest INS sample
  bool deskew = true;                         ///< motion-compensate scans with the INS twist
  double deskew_twist_max_gap_s = 0.2;        ///< INS sample within this of mid-scan [s]
  double scan_arrival_delay_s = 0.0;          ///< scan available at stamp + this [s]
  double time_backwards_tolerance_s = 1.0;    ///< scan stamp regression that resets [s]
  bool configured_pose_on_reset = true;       ///< re-arm the configured pose after a reset
  bool record_traversal = false;              ///< keep each search's traversal in its report
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
  /// Like the matcher's configured initial pose: searched with the wide window at the next
  /// scan (not carried by odometry), and again after each reset when configured_pose_on_reset.
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
  /// A merged scan in base_link; processing_latency_s: how long its match takes [s] (< 0:
  /// measured with options.clock).
  void addScan(ScanInput scan, double processing_latency_s);
  /// Completes the running and the waiting scan (end of input).
  void flush();

  /// Reports of the scans completed since the last call, in completion order.
  std::vector<PipelineScanReport> takeReports();
  /// The filter's state at time_s (fails when the filter is not running).
  Result<EkfState> stateAt(double time_s) const { return filter_.stateAt(time_s); }
  const LocalizationFilter& filter() const { return filter_; }
  const PriorTracker& tracker() const { return tracker_; }
  const OdometryBuffer& odometry() const { return odometry_; }
  const LocalizerPipelineOptions& options() const { return options_; }
  uint64_t droppedScans() const { return dropped_total_; }
  uint64_t resets() const { return resets_; }

 private:
  LocalizerPipeline(const LocalizerPipelineOptions& options, LocalizationFilter filter,
                    MatchProcessor processor);
  void advanceTo(double t);
  void complete();
  void start(ScanInput scan, double arrival_s, double start_s, double latency_s);
  void resetMatcher();

  LocalizerPipelineOptions options_;
  LocalizationFilter filter_;
  MatchProcessor processor_;
  PriorTracker tracker_;
  OdometryBuffer odometry_;
  std::shared_ptr<const ChunkMap> map_;
  std::optional<Pose6> configured_pose_;
  bool configured_z_known_ = true;
  std::optional<WindowExtent> configured_window_;

  std::optional<PipelineScanReport> in_flight_;
  std::optional<ScanInput> waiting_;
  double waiting_arrival_s_ = 0.0;
  double waiting_latency_s_ = 0.0;
  uint32_t dropped_since_report_ = 0;
  uint64_t dropped_total_ = 0;
  uint64_t resets_ = 0;
  bool have_last_scan_ = false;
  double last_scan_stamp_s_ = 0.0;
  std::vector<PipelineScanReport> reports_;
};

/// The twist used to deskew a scan: the INS sample nearest to the middle of the revolution
/// (stamp + half the largest point time) within max_gap_s; else the posterior's twist when the
/// tracker holds one within max_gap_s of the stamp; else none. Shared by the matcher nodelet.
std::optional<BodyTwist> deskewTwist(const ScanInput& scan, const OdometryBuffer& odometry,
                                     const PriorTracker& tracker, double max_gap_s);

/// The posterior the ekf nodelet publishes, from a filter state.
PosteriorEstimate posteriorFromState(const EkfState& state);

}  // namespace gmm_localization
