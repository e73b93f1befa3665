// Where the vehicle is: TF map -> base_link, the pose hint, the configured initial position.
#include <cmath>

#include "gmm_localization/ros/map_server.h"

namespace gmm_localization {
namespace node {

void MapServer::onPoseHint(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  const auto& p = msg->pose.pose.position;
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
    ROS_WARN_THROTTLE(5.0, "%s: ignoring a pose_hint with a non-finite position", name_.c_str());
    return;
  }
  if (!msg->header.frame_id.empty() && msg->header.frame_id != options_.map_frame) {
    ROS_WARN_THROTTLE(5.0, "%s: ignoring a pose_hint in frame '%s' (expected '%s')", name_.c_str(),
                      msg->header.frame_id.c_str(), options_.map_frame.c_str());
    return;
  }
  {
    std::lock_guard<std::mutex> lock(position_mutex_);
    hint_ = PlanCentre(p.x, p.y);
    hint_time_ = ros::WallTime::now();
  }
  ROS_INFO("%s: pose hint (%.1f, %.1f) m: serving chunks there", name_.c_str(), p.x, p.y);
  onUpdate();
}

CentreSelection MapServer::locateVehicle() {
  PositionSources sources;
  std::string tf_error;
  try {
    const geometry_msgs::TransformStamped t =
        tf_buffer_.lookupTransform(options_.map_frame, options_.base_frame, ros::Time(0));
    const PlanCentre p(t.transform.translation.x, t.transform.translation.y);
    if (std::isfinite(p.x()) && std::isfinite(p.y())) {
      sources.tf = p;
    } else {
      tf_error = "TF gives a non-finite position";
    }
  } catch (const tf2::TransformException& e) {
    tf_error = e.what();
  }
  const ros::WallTime now = ros::WallTime::now();
  std::lock_guard<std::mutex> lock(position_mutex_);
  if (sources.tf) {
    last_tf_ = sources.tf;
    last_tf_time_ = now;
  }
  sources.last_tf = last_tf_;
  sources.last_tf_age_s = (now - last_tf_time_).toSec();
  sources.hint = hint_;
  sources.hint_age_s = (now - hint_time_).toSec();
  sources.initial = options_.initial_position;
  centres_ = selectCentres(sources, options_.pose_hint_hold_s);
  tf_error_ = tf_error;
  if (centres_.centres.empty()) {
    ROS_WARN_THROTTLE(10.0,
                      "%s: no vehicle position yet (TF %s -> %s: %s; no pose_hint, no "
                      "initial_position): no chunk served",
                      name_.c_str(), options_.map_frame.c_str(), options_.base_frame.c_str(),
                      tf_error.c_str());
  }
  return centres_;
}

}  // namespace node
}  // namespace gmm_localization
