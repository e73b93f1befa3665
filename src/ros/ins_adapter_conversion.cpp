#include "gmm_localization/ros/ins_adapter_conversion.h"

#include <tf2/exceptions.h>

#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {

InsReport insReportFromMsg(const nav_msgs::Odometry& msg) {
  InsReport r;
  r.stamp_s = msg.header.stamp.toSec();
  const auto& p = msg.pose.pose.position;
  r.position = Eigen::Vector3d(p.x, p.y, p.z);
  const auto& q = msg.pose.pose.orientation;
  r.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z);
  const auto& v = msg.twist.twist.linear;
  const auto& w = msg.twist.twist.angular;
  r.linear_velocity = Eigen::Vector3d(v.x, v.y, v.z);
  r.angular_velocity = Eigen::Vector3d(w.x, w.y, w.z);
  r.pose_covariance = covarianceFromMsg(msg.pose.covariance);
  r.twist_covariance = covarianceFromMsg(msg.twist.covariance);
  return r;
}

const char* insAdapterOutcomeName(InsAdapterOutcome o) {
  switch (o) {
    case InsAdapterOutcome::kPublished:
      return "published";
    case InsAdapterOutcome::kNoTransform:
      return "no transform";
    case InsAdapterOutcome::kInvalid:
      return "invalid";
    case InsAdapterOutcome::kOutOfOrder:
      return "out of order";
  }
  return "?";
}

InsOdometryAdapter::InsOdometryAdapter(const InsAdapterOptions& options)
    : options_(options), odometry_(options.odometry) {}

const Eigen::Isometry3d* InsOdometryAdapter::extrinsic(const std::string& child_frame) const {
  const auto it = extrinsics_.find(child_frame);
  return it == extrinsics_.end() ? nullptr : &it->second;
}

InsAdapterResult InsOdometryAdapter::process(const nav_msgs::Odometry& msg,
                                             const tf2::BufferCore& tf) {
  InsAdapterResult out;
  std::string child = options_.child_frame.empty() ? msg.child_frame_id : options_.child_frame;
  if (child.empty()) child = options_.base_frame;
  out.child_frame = child;

  Eigen::Isometry3d base_T_child = Eigen::Isometry3d::Identity();
  if (child != options_.base_frame) {
    auto it = extrinsics_.find(child);
    if (it == extrinsics_.end()) {
      try {
        const auto t = tf.lookupTransform(options_.base_frame, child, ros::Time(0));
        const Eigen::Isometry3d T = fromMsg(t.transform);
        if (!T.matrix().allFinite()) {
          out.outcome = InsAdapterOutcome::kNoTransform;
          out.reason = "TF " + options_.base_frame + " <- " + child + " is not finite";
          return out;
        }
        it = extrinsics_.emplace(child, T).first;
      } catch (const tf2::TransformException& e) {
        out.outcome = InsAdapterOutcome::kNoTransform;
        out.reason = "no TF " + options_.base_frame + " <- " + child + ": " + e.what();
        return out;
      }
    }
    base_T_child = it->second;
  }

  const auto sample = insSampleInBaseLink(insReportFromMsg(msg), options_.convention, base_T_child,
                                          options_.covariance_defaults);
  if (!sample) {
    out.outcome = InsAdapterOutcome::kInvalid;
    out.reason = sample.error();
    return out;
  }
  const InsOdometry::Update u = odometry_.add(*sample);
  out.step = u.step;
  out.dt_s = u.dt_s;
  if (u.step == InsOdometryStep::kDroppedOutOfOrder) {
    out.outcome = InsAdapterOutcome::kOutOfOrder;
    out.reason = "stamp " + std::to_string(sample->stamp_s) + " not after the newest, " +
                 std::to_string(odometry_.stamp());
    return out;
  }

  out.outcome = InsAdapterOutcome::kPublished;
  nav_msgs::Odometry& o = out.odometry;
  o.header.stamp = msg.header.stamp;
  o.header.frame_id = options_.odom_frame;
  o.child_frame_id = options_.base_frame;
  o.pose.pose = toMsg(u.odom_T_base);
  if (options_.odometry.pose_source == InsPoseSource::kDriver) {
    covarianceToMsg(sample->pose_covariance, o.pose.covariance);
  }
  o.twist.twist.linear.x = sample->twist(0);
  o.twist.twist.linear.y = sample->twist(1);
  o.twist.twist.linear.z = sample->twist(2);
  o.twist.twist.angular.x = sample->twist(3);
  o.twist.twist.angular.y = sample->twist(4);
  o.twist.twist.angular.z = sample->twist(5);
  covarianceToMsg(sample->twist_covariance, o.twist.covariance);

  out.transform.header = o.header;
  out.transform.child_frame_id = o.child_frame_id;
  toMsg(u.odom_T_base, out.transform.transform);
  return out;
}

}  // namespace node
}  // namespace gmm_localization
