// EkfNode inputs and the relocalize service (ekf_node.h).
#include <cmath>

#include <tf2_eigen/tf2_eigen.h>

#include "gmm_localization/ros/ekf_node.h"
#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

/// Outcomes of a message dropped for its stamp (stale, too old, far ahead, or the one that
/// reports time going backwards): worth a log line with the reason, they are counted in the
/// filter's diagnostics.
bool droppedForItsStamp(FuseOutcome o) {
  return o == FuseOutcome::kRejectedStale || o == FuseOutcome::kRejectedTooOld ||
         o == FuseOutcome::kTimeJumpedForward || o == FuseOutcome::kTimeWentBackwards;
}

}  // namespace

std::optional<Eigen::Quaterniond> EkfNode::imuRotation(const std::string& frame) {
  if (frame.empty() || frame == options_.base_frame) return Eigen::Quaterniond::Identity();
  auto it = imu_rotations_.find(frame);
  if (it != imu_rotations_.end()) return it->second;
  try {
    // A static extrinsic: looked up once.
    const auto t = tf_buffer_.lookupTransform(options_.base_frame, frame, ros::Time(0));
    const Eigen::Quaterniond q(tf2::transformToEigen(t).linear());
    imu_rotations_[frame] = q;
    return q;
  } catch (const tf2::TransformException& e) {
    ROS_WARN_THROTTLE(5.0, "%s: IMU sample dropped: no TF from '%s' to '%s': %s", name_.c_str(),
                      frame.c_str(), options_.base_frame.c_str(), e.what());
    return std::nullopt;
  }
}

void EkfNode::handleEvents() {
  for (const FilterEvent& e : filter_->takeEvents()) {
    last_event_ = std::string(filterEventName(e.kind)) + ": " + e.detail;
    switch (e.kind) {
      case FilterEventKind::kInitializedFromPose:
      case FilterEventKind::kInitializedFromMatch:
      case FilterEventKind::kRelocalizeRequest:
      case FilterEventKind::kStartDeferred:
        ROS_INFO("%s: %s at %.3f", name_.c_str(), last_event_.c_str(), e.stamp_s);
        break;
      case FilterEventKind::kStoppedTimeBackwards:
      case FilterEventKind::kStoppedTimeJump:
        ROS_WARN("%s: %s; filter stopped, waiting for an initial pose or a scan match",
                 name_.c_str(), last_event_.c_str());
        break;
      case FilterEventKind::kGateLockout:
      case FilterEventKind::kMatcherRelocalizing:
      case FilterEventKind::kMatcherLost:
        ROS_WARN("%s: %s", name_.c_str(), last_event_.c_str());
        break;
    }
  }
}

void EkfNode::onImu(const sensor_msgs::Imu::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  imu_rate_.tick();
  imu_rate_.stamp(msg->header.stamp);
  inputs_.heard(imu_input_, ros::WallTime::now().toSec());
  const auto rotation = imuRotation(msg->header.frame_id);
  if (!rotation) return;
  const auto imu = imuFromMsg(*msg, *rotation);
  if (!imu) {
    ++bad_inputs_;
    ROS_WARN_THROTTLE(5.0, "%s: IMU sample ignored: %s", name_.c_str(), imu.error().c_str());
    return;
  }
  bool invalid = false;  // counted once per message, whatever its parts
  for (const FuseReport& r : filter_->addImu(*imu)) {
    if (r.outcome == FuseOutcome::kRejectedInvalid) {
      invalid = true;
      ROS_WARN_THROTTLE(5.0, "%s: %s", name_.c_str(), r.reason.c_str());
    } else if (droppedForItsStamp(r.outcome)) {
      ROS_WARN_THROTTLE(5.0, "%s: IMU message dropped (%s): %s", name_.c_str(),
                        outcomeName(r.outcome), r.reason.c_str());
    }
  }
  bad_inputs_ += invalid ? 1 : 0;
  handleEvents();
}

void EkfNode::onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  odom_rate_.tick();
  odom_rate_.stamp(msg->header.stamp);
  inputs_.heard(odom_input_, ros::WallTime::now().toSec());
  if (!msg->child_frame_id.empty() && msg->child_frame_id != options_.base_frame) {
    ROS_WARN_THROTTLE(10.0,
                      "%s: INS odometry child frame '%s' is not '%s'; its twist is used "
                      "as if it were",
                      name_.c_str(), msg->child_frame_id.c_str(), options_.base_frame.c_str());
  }
  const OdometrySample sample = odometrySampleFromMsg(*msg);
  // A stale message (its stamp beyond the tolerance before the running filter) must not
  // replace the newest pose either: map -> odom would fall back to a pose seconds old.
  const bool stale =
      filter_->active() &&
      sample.stamp_s < filter_->ekf().time() - options_.ekf.time_backwards_tolerance_s;
  if (sample.odom_T_base.matrix().allFinite() && !stale) last_odom_ = sample;
  if (!options_.use_odom_twist) return;
  const FuseReport r = filter_->addTwist(twistFromOdometryMsg(*msg));
  if (r.outcome == FuseOutcome::kRejectedInvalid) {
    ++bad_inputs_;
    ROS_WARN_THROTTLE(5.0, "%s: INS twist ignored: %s", name_.c_str(), r.reason.c_str());
  } else if (droppedForItsStamp(r.outcome)) {
    ROS_WARN_THROTTLE(5.0, "%s: INS odometry message dropped (%s): %s", name_.c_str(),
                      outcomeName(r.outcome), r.reason.c_str());
  }
  handleEvents();
}

void EkfNode::onMatch(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  inputs_.heard(match_input_, ros::WallTime::now().toSec());
  if (msg->header.frame_id != options_.map_frame) {
    ++bad_inputs_;
    ROS_WARN_THROTTLE(5.0, "%s: scan match in frame '%s' ignored (expected '%s')", name_.c_str(),
                      msg->header.frame_id.c_str(), options_.map_frame.c_str());
    return;
  }
  const auto pose = poseFromMsg(*msg);
  if (!pose) {
    ++bad_inputs_;
    ROS_WARN_THROTTLE(5.0, "%s: scan match ignored: %s", name_.c_str(), pose.error().c_str());
    return;
  }
  const FuseReport r = filter_->addMatch(pose->stamp_s, pose->pose, pose->covariance);
  if (r.fused()) {
    last_fused_match_wall_ = ros::WallTime::now();
    last_fused_match_stamp_s_ = pose->stamp_s;
  } else if (r.outcome == FuseOutcome::kRejectedGate) {
    ROS_WARN_THROTTLE(2.0, "%s: scan match rejected by the Mahalanobis gate (d = %.2f, gate %.2f)",
                      name_.c_str(), r.mahalanobisDistance(), std::sqrt(r.gate_threshold_sq));
  } else {
    ROS_WARN_THROTTLE(5.0, "%s: scan match not fused (%s): %s", name_.c_str(),
                      outcomeName(r.outcome), r.reason.c_str());
  }
  handleEvents();
}

void EkfNode::onMatchStatus(const MatchStatus::ConstPtr& msg) {
  const std::optional<PriorMode> mode = priorModeFromName(msg->prior_mode);
  if (!mode) return;  // an older matcher without the field: nothing to follow
  std::lock_guard<std::mutex> lock(mutex_);
  filter_->onMatcherMode(msg->header.stamp.toSec(), *mode);
  handleEvents();
}

void EkfNode::onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto pose = initialPoseInMap(*msg, options_.map_frame, tf_buffer_);
  if (!pose) {
    ++bad_inputs_;
    last_event_ = "initial pose ignored: " + pose.error();
    ROS_WARN("%s: %s", name_.c_str(), last_event_.c_str());
    return;
  }
  const double stamp = msg->header.stamp.isZero() ? ros::Time::now().toSec() : pose->stamp_s;
  const Status s = filter_->setInitialPose(pose->pose, pose->covariance, stamp, false);
  if (!s) {
    ++bad_inputs_;
    last_event_ = "initial pose rejected: " + s.error();
    ROS_WARN("%s: %s", name_.c_str(), last_event_.c_str());
  }
  handleEvents();
}

bool EkfNode::onRelocalize(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const double t = filter_->active() ? filter_->ekf().time() : ros::Time::now().toSec();
  const Status s = filter_->relocalize(t);
  res.success = s.ok();
  res.message = s.ok() ? "covariance inflated: the matcher searches its widest window next"
                       : "relocalize refused: " + s.error();
  handleEvents();
  return true;
}

}  // namespace node
}  // namespace gmm_localization
