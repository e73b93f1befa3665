// EkfNode's optional GNSS input (gnss/enabled, ekf_node.h): NavSatFix -> the core's GnssFix
// (gnss_conversion.h, shared with the GNSS initializer), the lever arm from TF, the map's
// georeference from the map server's index; LocalizationFilter::addGnss fuses and gates it.
#include <tf2_eigen/tf2_eigen.h>

#include "gmm_localization/ros/ekf_node.h"
#include "gmm_localization/ros/gnss_conversion.h"
#include "gmm_localization/ros/map_server_client.h"

namespace gmm_localization {
namespace node {

void EkfNode::setupGnss() {
  if (!options_.filter.gnss_enabled) return;
  gnss_input_ = inputs_.add(nh_.resolveName(options_.gnss_topic), /*watch_silence=*/false);
  gnss_sub_ = nh_.subscribe(options_.gnss_topic, 20, &EkfNode::onGnssFix, this);
  index_sub_ = nh_.subscribe("map_index", 2, &EkfNode::onMapIndex, this);
  ROS_INFO("%s: GNSS input on %s (gated, placed with the map index's georeference)", name_.c_str(),
           nh_.resolveName(options_.gnss_topic).c_str());
}

void EkfNode::onMapIndex(const MapIndex::ConstPtr& msg) {
  const Georeference g = georeferenceOf(*msg);
  std::lock_guard<std::mutex> lock(mutex_);
  filter_->setGeoreference(g);
  have_georeference_ = g.hasGrid();
  georeference_text_ = g.describe();
  if (!have_georeference_) {
    ROS_WARN(
        "%s: the map has no georeference with a UTM zone (%s): GNSS fixes are refused; "
        "rebuild the map with build_map --utm-zone ... --georef-origin ...",
        name_.c_str(), georeference_text_.c_str());
  }
}

void EkfNode::onGnssFix(const sensor_msgs::NavSatFix::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++gnss_fixes_;
  inputs_.heard(gnss_input_, ros::WallTime::now().toSec());
  const std::string& frame = msg->header.frame_id;
  if (!frame.empty() && frame != options_.base_frame) {
    try {
      const auto t = tf_buffer_.lookupTransform(options_.base_frame, frame, ros::Time(0));
      filter_->setGnssLeverArm(tf2::transformToEigen(t).translation());
    } catch (const tf2::TransformException& e) {
      gnss_last_problem_ = "no TF from '" + frame + "' to '" + options_.base_frame + "'";
      ROS_WARN_THROTTLE(10.0, "%s: GNSS fix dropped: %s: %s", name_.c_str(),
                        gnss_last_problem_.c_str(), e.what());
      return;
    }
  } else {
    filter_->setGnssLeverArm(Eigen::Vector3d::Zero());
  }
  const FuseReport r = filter_->addGnss(gnssFixFromMsg(*msg));
  if (r.fused() || r.outcome == FuseOutcome::kRejectedNotInitialized) return;
  gnss_last_problem_ = r.reason.empty() ? outcomeName(r.outcome) : r.reason;
  if (r.outcome == FuseOutcome::kRejectedGate) {
    ROS_WARN_THROTTLE(10.0, "%s: GNSS fix rejected by the Mahalanobis gate (d = %.1f)",
                      name_.c_str(), r.mahalanobisDistance());
  } else {
    ROS_WARN_THROTTLE(10.0, "%s: %s", name_.c_str(), gnss_last_problem_.c_str());
  }
  handleEvents();
}

}  // namespace node
}  // namespace gmm_localization
