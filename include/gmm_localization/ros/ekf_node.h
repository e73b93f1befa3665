#pragma once
// The ekf nodelet: LocalizationFilter (core Ekf + the shared policy,
// core/localization/localization_filter.h) fed with the IMU, the INS twist and the matcher's poses;
// publishes the estimate and the REP-105 map->odom transform at a steady rate.
//
// Subscribed (relative names; remap in launch):
//   imu          sensor_msgs/Imu (any frame with a TF to base_frame; covariance[0] == -1: part
//                absent; all-zero covariance: configured defaults)
//   odom         nav_msgs/Odometry from the INS: body twist fused; its pose is the fallback for
//                odom->base_link when TF has none
//   pose         geometry_msgs/PoseWithCovarianceStamped, the matcher's matches in map_frame
//                (delayed measurements, Mahalanobis-gated in the core; the first one starts the
//                filter when nothing else did)
//   gnss/topic   sensor_msgs/NavSatFix (parameter, only with gnss/enabled): base_link's position
//                from the fix (lever arm from TF base_frame <- the fix's frame), placed in the map
//                by the georeference of `map_index` (the map server's), Mahalanobis-gated
//   map_index    gmm_localization/MapIndex (only with gnss/enabled): the map's georeference
//   initialpose  geometry_msgs/PoseWithCovarianceStamped (rviz): (re)starts the filter there,
//                planar (z, roll, pitch kept from the filter), x/y/yaw variance raised to the
//                relocalization sigmas so the matcher's wide-window match passes the gate
// Service:
//   relocalize   std_srvs/Trigger: inflates x, y, yaw to the relocalization sigmas; the
//                matcher's next window (3 sigma, clamped) is then its maximum.
// Published:
//   odometry     nav_msgs/Odometry in map_frame, child base_frame: stateAt(now) with pose and
//                twist covariances, at publish_rate_hz, only while the filter runs
//   TF map->odom = map_T_base(t) * odom_T_base(t)^-1 with t the newest odom->base_link TF,
//                stamped now, at the same rate
// A single message stamped stale (beyond time_backwards_tolerance_s) or far ahead is dropped
// with a throttled warning naming the reason and counted in diagnostics; time going backwards
// (a looping bag: a run of stale_reset_count stale messages, or one beyond
// time_backwards_reset_s) or forward_jump_reset_count far-future messages in a row stop the
// filter until an initial pose or a match;
// consecutive gate rejections inflate the covariance (see LocalizationFilter). Nothing
// non-finite is ever published. Callbacks and the timer run serialised on the nodelet's queue.
// Diagnostics (ekf_node_diagnostics.cpp): "filter", "inputs" and "<topic> topic status" of the
// IMU and the INS odometry (rate and stamp age, diagnostics.h); an input silent for 5 s gets a
// console line naming the topic and the launch argument or parameter that fixes it.

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/core/common/input_watchdog.h"
#include "gmm_localization/core/localization/localization_filter.h"
#include "gmm_localization/core/localization/prior_tracker.h"
#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/ekf_node_options.h"

namespace gmm_localization {
namespace node {

class EkfNode {
 public:
  /// Loads the options (throws ConfigError with the reason), subscribes, starts the timer.
  EkfNode(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~EkfNode();
  EkfNode(const EkfNode&) = delete;
  EkfNode& operator=(const EkfNode&) = delete;

 private:
  // ekf_node_callbacks.cpp: inputs and the service.
  void onImu(const sensor_msgs::Imu::ConstPtr& msg);
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg);
  void onMatch(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  void onMatchStatus(const MatchStatus::ConstPtr& msg);
  // ekf_node_gnss.cpp: the optional GNSS input.
  void setupGnss();
  void onGnssFix(const sensor_msgs::NavSatFix::ConstPtr& msg);
  void onMapIndex(const MapIndex::ConstPtr& msg);
  bool onRelocalize(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  std::optional<Eigen::Quaterniond> imuRotation(const std::string& frame);
  void handleEvents();  // needs mutex_
  // ekf_node_publish.cpp: the timer.
  void onTimer(const ros::TimerEvent& event);
  std::optional<Eigen::Isometry3d> mapToOdom(const EkfState& now_state);
  // ekf_node_diagnostics.cpp
  void setupDiagnostics();
  /// The console lines of the inputs silent for 5 s (inputs_); needs mutex_.
  void warnSilentInputs(double now_s);

  const std::string name_;
  ros::NodeHandle nh_, pnh_;
  EkfNodeOptions options_;
  std::unique_ptr<LocalizationFilter> filter_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Subscriber imu_sub_, odom_sub_, match_sub_, initialpose_sub_, status_sub_;
  ros::Subscriber gnss_sub_, index_sub_;  ///< gnss/enabled only
  ros::ServiceServer relocalize_srv_;
  ros::Publisher odometry_pub_;
  ros::Timer timer_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex mutex_;  ///< everything below (the diagnostics timer runs on its own queue)
  std::map<std::string, Eigen::Quaterniond> imu_rotations_;
  std::optional<OdometrySample> last_odom_;
  FrequencyMonitor imu_rate_, odom_rate_;  ///< the topics' rate and stamps (thread-safe)
  std::string imu_topic_, odom_topic_;     ///< resolved
  InputWatchdog inputs_;                   ///< wall time
  size_t imu_input_ = 0, odom_input_ = 0, match_input_ = 0, gnss_input_ = 0;
  bool have_georeference_ = false;  ///< a map index was received (gnss/enabled)
  std::string georeference_text_ = "no map index yet";
  uint64_t gnss_fixes_ = 0;  ///< NavSatFix messages received
  std::string gnss_last_problem_;
  ros::WallTime last_fused_match_wall_;
  double last_fused_match_stamp_s_ = NAN;
  ros::Time last_stamp_;  ///< of the last published estimate
  uint64_t bad_inputs_ = 0, published_ = 0, publish_failures_ = 0;
  std::string last_event_;
  std::string last_publish_problem_;
};

}  // namespace node
}  // namespace gmm_localization
