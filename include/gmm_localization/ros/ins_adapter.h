#pragma once
// The INS adapter: turns a real INS driver's nav_msgs/Odometry (world-frame velocity, FRD body,
// solution at the INS reference point) into what the matcher and the EKF read: odometry in
// odom_frame with child base_frame, the twist of base_link in base_link, the pose odom ->
// base_link dead-reckoned from it (or the driver's pose); optionally TF odom -> base_link.
//
// Topics (relative; remap in launch):
//   driver_odom  nav_msgs/Odometry in: the driver's odometry (conventions: driver_preset and
//                velocity_frame / body_axes / attitude, config/ins_adapter.yaml).
//   ins_odom     nav_msgs/Odometry out: odom_frame -> base_frame, one per accepted input, same
//                stamp; twist covariance propagated to base_link (zeros when the driver gives
//                none); pose covariance zeros with dead reckoning, the driver's (position block
//                in ENU) with pose_source driver.
// TF: base_frame <- the driver's child frame (the lever arm; static) in; odom_frame ->
// base_frame out with publish_tf (the driver must then not publish its own odom TF).
// Messages dropped (no TF yet, not finite, a bad quaternion, out of order) are counted and
// logged (throttled); a stamp more than backwards_reset_s older than the newest restarts the
// odometry at the origin. Diagnostics: "<name>: INS adapter".
// The work on each message is InsOdometryAdapter (ins_adapter_conversion.h).

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/ins_adapter_conversion.h"

namespace gmm_localization {
namespace node {

class InsAdapter {
 public:
  /// Throws ConfigError on a bad parameter.
  InsAdapter(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~InsAdapter();
  InsAdapter(const InsAdapter&) = delete;
  InsAdapter& operator=(const InsAdapter&) = delete;

 private:
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void setUpDiagnostics();

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::Subscriber sub_;
  ros::Publisher pub_;
  FrequencyMonitor input_rate_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex mutex_;  // guards the adapter and every counter
  InsOdometryAdapter adapter_;
  uint64_t received_ = 0, published_ = 0, no_tf_ = 0, invalid_ = 0, out_of_order_ = 0;
  uint64_t restarts_ = 0, gaps_ = 0;
  std::string last_child_frame_;
  ProblemLog problems_;  ///< its latest problem (WARN throttled)
};

}  // namespace node
}  // namespace gmm_localization
