// EkfNode set-up (see ekf_node.h).
#include "gmm_localization/ros/ekf_node.h"

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

EkfNode::EkfNode(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : name_(name),
      nh_(nh),
      pnh_(pnh),
      options_(loadNodeletOptions(pnh, name, loadEkfNodeOptions)),
      tf_listener_(tf_buffer_),
      imu_rate_(0.0, 1e9),
      odom_rate_(0.0, 1e9),
      match_rate_(0.0, 1e9) {
  auto filter = LocalizationFilter::create(options_.ekf, options_.filter);
  if (!filter) throw ConfigError(filter.error());
  filter_ = std::make_unique<LocalizationFilter>(std::move(filter).value());

  odometry_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry", 20);
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  if (options_.use_imu) imu_sub_ = nh_.subscribe("imu", 400, &EkfNode::onImu, this, hints);
  odom_sub_ = nh_.subscribe("odom", 200, &EkfNode::onOdom, this, hints);
  match_sub_ = nh_.subscribe("pose", 20, &EkfNode::onMatch, this, hints);
  initialpose_sub_ = nh_.subscribe("initialpose", 2, &EkfNode::onInitialPose, this);
  relocalize_srv_ = nh_.advertiseService("relocalize", &EkfNode::onRelocalize, this);
  timer_ = nh_.createTimer(ros::Duration(1.0 / options_.publish_rate_hz), &EkfNode::onTimer, this);
  setupDiagnostics();
  ROS_INFO(
      "%s: EKF in '%s' (odom '%s', base '%s'), publishing at %.1f Hz; waiting for an "
      "initial pose or a scan match",
      name_.c_str(), options_.map_frame.c_str(), options_.odom_frame.c_str(),
      options_.base_frame.c_str(), options_.publish_rate_hz);
}

EkfNode::~EkfNode() {
  // No callback, timer or diagnostics task may run while the members go away.
  timer_.stop();
  for (ros::Subscriber* sub : {&imu_sub_, &odom_sub_, &match_sub_, &initialpose_sub_}) {
    sub->shutdown();
  }
  relocalize_srv_.shutdown();
  diagnostics_.reset();
}

}  // namespace node
}  // namespace gmm_localization
