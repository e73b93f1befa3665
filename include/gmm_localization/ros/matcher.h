#pragma once
// The matcher: registers each merged scan in the rasterized map (paper Algorithm 1:
// branch-and-bound search + hill climb) around a prior and publishes the pose with the
// search-space covariance. The per-scan logic is the ROS-free MatchSession (prior tracking, the
// time rule, the scan queue, the outcome handling; core/localization/match_session.h) and
// MatchProcessor (core/localization/match_processor.h), shared with LocalizerPipeline, so
// `evaluate` reproduces what this node does.
//
// Subscribed (relative names; remap in launch):
//   velodyne_points  sensor_msgs/PointCloud2, merged scan in base_frame (another frame is moved
//                    into base_frame with TF at the scan stamp, rigidly); per-point `time`
//                    deskews it with the INS twist
//   odom             nav_msgs/Odometry, INS (odom -> base_link): twist for deskewing, poses to
//                    carry the EKF posterior to the scan stamp
//   odometry         nav_msgs/Odometry, the EKF posterior (map frame) = the tracking prior
//   initialpose      geometry_msgs/PoseWithCovarianceStamped (rviz "2D Pose Estimate"; z, roll,
//                    pitch completed from the posterior/INS): wide window around it
//   map_chunks       gmm_localization/RasterChunk (zero copy via node::fromMsg)
//   map_index        gmm_localization/MapIndex (latched): protocol of map_server_client.h
//   reflectivity/map_chunks, reflectivity/map_index  method fused only: the reflectivity layer
//                    from a second map server (matcher_reflectivity.cpp); until it has arrived,
//                    or while the two layers cannot be searched together, every scan is
//                    answered skipped with the reason
// Published:
//   pose             geometry_msgs/PoseWithCovarianceStamped, accepted matches, scan stamp, map
//   status           gmm_localization/MatchStatus, one per processed scan (accepted or why not)
//                    plus one when time went backwards
//   obstacles        sensor_msgs/PointCloud2 of obstacle points (obstacles_frame)  [on demand]
//   scan_classified  sensor_msgs/PointCloud2, scan in map with mahalanobis + class [on demand]
//   search_traversal sensor_msgs/Image, the branch-and-bound traversal (Fig. 9)   [on demand]
// Service:
//   global_localization  std_srvs/Trigger: search the global window (window/global_max_*, the
//                    full turn) around the current estimate from the next scan until a match is
//                    accepted (certified: acceptance/require_certificate_wide); refused with the
//                    reason when there is no pose to search around
// Diagnostics (matcher_diagnostics.cpp): "scan matching" and "<scan topic> topic status" (rate
// and stamp age, diagnostics.h). Console lines naming the fix: no scans for 5 s (the topic and
// the launch argument points_topic), scans but no pose to search around (/initialpose,
// initial_pose/*), and an explicit pose rejected scan after scan with none accepted, even by
// the global search once lost (core/localization/acquisition_watch.h).
// Threads: ROS callbacks (serialised, non-blocking), one worker and one global worker. Scans
// wait in the session's queue (scan_queue_size, oldest dropped when full, drops counted in the
// next status); the worker takes the oldest. A scan whose prior is lost (the global window) goes
// to the global worker when it is idle, and the worker goes on with the next scans while it
// runs (MatchSessionState::beginMatch: skipped when the estimate is not trusted, else searched
// in the interim window, Prior::interim): a search of seconds never stops the others.
// The session is not synchronised: session_mutex_ guards every call, never held during a
// match. Both workers search a snapshot of the map (immutable shared chunks): chunk callbacks
// never wait for a match.

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/common/input_watchdog.h"
#include "gmm_localization/core/localization/acquisition_watch.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/localization/match_session.h"
#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/map_server_client.h"
#include "gmm_localization/ros/matcher_options.h"

namespace gmm_localization {
namespace node {

/// The nodelet's session: scans wait as received and are converted by the worker.
using MatcherSession = MatchSession<sensor_msgs::PointCloud2::ConstPtr>;
/// The session the nodelet runs with these options: options.session with options.policy, and
/// the configured initial pose (with configuredPoseWindow()) armed when initial_pose_enabled.
MatcherSession makeMatcherSession(const MatcherOptions& options);

class Matcher {
 public:
  /// Loads the options (throws ConfigError with the reason), subscribes and starts the worker.
  Matcher(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~Matcher();
  Matcher(const Matcher&) = delete;
  Matcher& operator=(const Matcher&) = delete;

 private:
  // matcher_inputs.cpp: INS, posterior, initial pose, map.
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg);
  void onPosterior(const nav_msgs::Odometry::ConstPtr& msg);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  bool onGlobalLocalization(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  // With the publisher: the client follows one map server and ignores the others.
  void onChunk(const ros::MessageEvent<const RasterChunk>& event);
  void onIndex(const ros::MessageEvent<const MapIndex>& event);
  // matcher_reflectivity.cpp: the fused method's second layer (a second map server).
  void onReflectivityChunk(const ros::MessageEvent<const RasterChunk>& event);
  void onReflectivityIndex(const ros::MessageEvent<const MapIndex>& event);
  /// Needs map_mutex_: refreshes layer_mismatch_ from both clients' indices.
  void checkLayers();
  /// Needs map_mutex_: why the fused method cannot search now (empty: it can).
  std::string reflectivityProblem() const;
  /// The second layer's diagnostics lines (method fused); returns its problem (empty: none),
  /// `mismatch` whether it is that the layers cannot be searched together.
  std::string addReflectivityDiagnostics(StatusBuilder& s, bool* mismatch);
  // matcher_worker.cpp: scan intake, the worker, one scan's processing.
  void onScan(const sensor_msgs::PointCloud2::ConstPtr& msg);
  void workerLoop();
  void globalWorkerLoop();
  void processScan(const sensor_msgs::PointCloud2::ConstPtr& msg, uint32_t dropped);
  /// Matches one converted scan from `start`, applies the outcome and publishes. `cancel`: the
  /// global worker's flag (MatchProcessor::process).
  void runMatch(const sensor_msgs::PointCloud2::ConstPtr& msg, ScanInput scan,
                const MatchStart& start, uint32_t dropped,
                const std::atomic<bool>* cancel = nullptr);
  /// fn(), or the failure status of msg when it throws (the scan is answered all the same).
  template <typename Fn>
  void answerEvenIfThrows(const sensor_msgs::PointCloud2::ConstPtr& msg, uint32_t dropped, Fn&& fn);
  bool scanToBase(const sensor_msgs::PointCloud2& msg, ScanInput* scan, std::string* reason);
  void publishSkipped(const ros::Time& stamp, const std::string& reason, uint32_t dropped);
  /// The status of a scan whose processing threw (counted in the diagnostics).
  void publishFailure(const sensor_msgs::PointCloud2::ConstPtr& msg, const std::string& reason,
                      uint32_t dropped);
  /// The pose first; then the obstacle labels (MatchProcessor::labelObstacles, on `map`), the
  /// status and the debug outputs.
  void publishOutputs(const ChunkMap& map, MatchReport& report, const ros::Time& stamp,
                      uint32_t dropped);
  // matcher_diagnostics.cpp
  void setupDiagnostics();
  void record(const MatchReport& report, uint32_t dropped);
  /// The console line of an explicit pose that is stuck (acquisition_), needs stats_mutex_.
  void warnStuck(const MatchReport& report);
  /// The silent-input and no-prior lines, from the diagnostics timer; needs stats_mutex_.
  void warnInputs(double now_s);

  const std::string name_;
  ros::NodeHandle nh_, pnh_;
  MatcherOptions options_;
  std::unique_ptr<MatchProcessor> processor_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;

  ros::Subscriber scan_sub_, odom_sub_, posterior_sub_, initialpose_sub_, chunk_sub_, index_sub_;
  ros::Subscriber reflectivity_chunk_sub_, reflectivity_index_sub_;  ///< method fused only
  ros::ServiceServer global_srv_;
  ros::Publisher pose_pub_, status_pub_, obstacles_pub_, classified_pub_, traversal_pub_;
  std::unique_ptr<Diagnostics> diagnostics_;

  // The session (prior tracking, time rule, scan queue), shared by the callbacks and the
  // worker; queue_cv_ wakes the worker when a scan is queued or stop_ is set.
  std::mutex session_mutex_;
  std::condition_variable queue_cv_;
  MatcherSession session_;
  bool stop_ = false;
  /// The global worker's scan (waiting or running); global_cv_ wakes it.
  struct GlobalJob {
    sensor_msgs::PointCloud2::ConstPtr msg;
    ScanInput scan;
    MatchStart start;
    uint32_t dropped = 0;
  };
  std::optional<GlobalJob> global_job_;  ///< handed over, not yet taken
  bool global_busy_ = false;             ///< a job handed over and not finished
  std::condition_variable global_cv_;
  /// Set by a new /initialpose while the global worker has a job (waiting or running): its
  /// search around the old pose stops (answered rejected, not counted against the new pose);
  /// cleared when a job is handed over. Written under session_mutex_.
  std::atomic<bool> global_cancel_{false};

  // The map: protocol state and the snapshot the worker searches.
  std::mutex map_mutex_;
  MapServerClient map_client_;
  std::shared_ptr<const ChunkMap> map_snapshot_;
  // The fused method's reflectivity layer (a second map server): protocol state, snapshot and
  // why the two layers cannot be searched together (empty: they can, or not both known yet).
  MapServerClient reflectivity_client_;
  std::shared_ptr<const ChunkMap> reflectivity_snapshot_;
  std::string layer_mismatch_;
  std::string reflectivity_topic_;  ///< resolved reflectivity/map_index

  std::thread worker_, global_worker_;

  // Diagnostics (stats_mutex_; scan_rate_ is thread-safe on its own).
  std::mutex stats_mutex_;
  FrequencyMonitor scan_rate_;  ///< the scan topic's rate and stamps
  std::string scan_topic_;      ///< resolved
  InputWatchdog inputs_;        ///< wall time
  size_t scans_input_ = 0, matches_input_ = 0;
  AcquisitionWatch acquisition_;
  std::string acquisition_source_;  ///< prior source of the explicit pose it counts
  LineThrottle no_prior_line_{30.0};
  double no_prior_since_s_ = -1.0;  ///< wall time the prior mode became no_prior with scans
  std::deque<bool> recent_accepted_;
  std::deque<bool> recent_certified_;  ///< of the accepted matches
  uint64_t certified_ = 0;
  std::string last_certificate_;
  double last_protection_xy_m_ = 0.0, last_separation_ = 0.0;
  uint64_t scans_ = 0, accepted_ = 0, time_resets_ = 0, bad_clouds_ = 0;
  uint64_t time_recalls_ = 0;         ///< resets recovered from the match history
  uint64_t processing_failures_ = 0;  ///< scans whose processing threw (answered all the same)
  /// Method fused: scans answered skipped because the reflectivity layer was missing or
  /// could not be searched with the height map.
  uint64_t reflectivity_skips_ = 0;
  std::string last_reason_;
  double last_ll_per_point_ = 0.0, last_search_ms_ = 0.0, last_total_ms_ = 0.0;
  WindowExtent last_window_;
  std::string last_prior_source_ = "none";
  std::string last_mode_ = "no_prior";
};

}  // namespace node
}  // namespace gmm_localization
