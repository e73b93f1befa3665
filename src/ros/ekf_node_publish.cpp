// EkfNode output: odometry and the map->odom transform on a steady timer (ekf_node.h).
#include <cmath>

#include <geometry_msgs/TransformStamped.h>
#include <tf2_eigen/tf2_eigen.h>

#include "gmm_localization/ros/ekf_node.h"
#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {

std::optional<Eigen::Isometry3d> EkfNode::mapToOdom(const EkfState& now_state) {
  // odom_T_base(t) from the INS TF (newest), else from the newest odom message.
  Eigen::Isometry3d odom_T_base;
  double t = NAN;
  try {
    const auto tf =
        tf_buffer_.lookupTransform(options_.odom_frame, options_.base_frame, ros::Time(0));
    odom_T_base = tf2::transformToEigen(tf);
    t = tf.header.stamp.toSec();
  } catch (const tf2::TransformException& e) {
    if (!last_odom_ ||
        std::abs(last_odom_->stamp_s - now_state.time_s) > options_.odom_pose_max_age_s) {
      last_publish_problem_ = "no " + options_.odom_frame + " -> " + options_.base_frame +
                              " transform (TF: " + e.what() + ") and no recent odom message";
      return std::nullopt;
    }
    odom_T_base = last_odom_->odom_T_base;
    t = last_odom_->stamp_s;
  }
  // map_T_base at the same time t (the filter's history covers recent times); map->odom is
  // nearly constant, so a TF a little older or newer than now is fine.
  const auto at_t = filter_->stateAt(t);
  const Eigen::Isometry3d map_T_base = at_t ? at_t->pose() : now_state.pose();
  const Eigen::Isometry3d map_T_odom = map_T_base * odom_T_base.inverse();
  if (!map_T_odom.matrix().allFinite()) {
    last_publish_problem_ = "non-finite map -> odom transform";
    return std::nullopt;
  }
  return map_T_odom;
}

void EkfNode::onTimer(const ros::TimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!filter_->active()) return;  // nothing before initialization
  const ros::Time now = ros::Time::now();
  auto state = filter_->stateAt(now.toSec());
  ros::Time stamp = now;
  if (!state) {
    // The clock is behind the filter's history (or far ahead: an input dropout).
    const double lag = filter_->ekf().time() - now.toSec();
    if (lag > 0.0) {
      state = filter_->ekf().state();
      stamp.fromSec(filter_->ekf().time());
    } else {
      ++publish_failures_;
      last_publish_problem_ = state.error();
      ROS_WARN_THROTTLE(5.0, "%s: no estimate published: %s", name_.c_str(), state.error().c_str());
      return;
    }
  }
  // A timer catching up (or a clock behind the filter) can repeat a stamp: publish each once.
  // A stamp far older than the last one is a new timeline (the clock went back).
  if (!last_stamp_.isZero() && stamp <= last_stamp_ &&
      stamp > last_stamp_ - ros::Duration(options_.ekf.time_backwards_tolerance_s)) {
    return;
  }
  last_stamp_ = stamp;
  nav_msgs::Odometry odom;
  if (!odometryMsgFromState(*state, options_.map_frame, options_.base_frame, odom)) {
    ++publish_failures_;
    last_publish_problem_ = "non-finite state";
    ROS_ERROR_THROTTLE(5.0, "%s: non-finite EKF state not published", name_.c_str());
    return;
  }
  odom.header.stamp = stamp;
  odometry_pub_.publish(odom);
  ++published_;
  if (!options_.publish_tf) return;
  const auto map_T_odom = mapToOdom(*state);
  if (!map_T_odom) {
    ++publish_failures_;
    ROS_WARN_THROTTLE(5.0, "%s: map -> odom not published: %s", name_.c_str(),
                      last_publish_problem_.c_str());
    return;
  }
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = options_.map_frame;
  tf.child_frame_id = options_.odom_frame;
  toMsg(*map_T_odom, tf.transform);
  tf_broadcaster_.sendTransform(tf);
}

}  // namespace node
}  // namespace gmm_localization
