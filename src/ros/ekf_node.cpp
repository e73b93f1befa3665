// EkfNode set-up (see ekf_node.h).
#include "gmm_localization/ros/ekf_node.h"

#include <limits>

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

EkfNode::EkfNode(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : name_(name),
      nh_(nh),
      pnh_(pnh),
      options_(loadNodeletOptions(pnh, name, loadEkfNodeOptions)),
      tf_listener_(tf_buffer_),
      // No rate is expected of the IMU and the INS: only "No events recorded." (and stamps).
      imu_rate_(0.0, std::numeric_limits<double>::infinity()),
      odom_rate_(0.0, std::numeric_limits<double>::infinity()) {
  auto filter = LocalizationFilter::create(options_.ekf, options_.filter);
  if (!filter) throw ConfigError(filter.error());
  filter_ = std::make_unique<LocalizationFilter>(std::move(filter).value());

  imu_topic_ = nh_.resolveName("imu");
  odom_topic_ = nh_.resolveName("odom");
  imu_input_ = inputs_.add(imu_topic_, /*watch_silence=*/options_.use_imu);
  odom_input_ = inputs_.add(odom_topic_);
  match_input_ = inputs_.add(nh_.resolveName("pose"), /*watch_silence=*/false);
  inputs_.start(ros::WallTime::now().toSec());

  odometry_pub_ = nh_.advertise<nav_msgs::Odometry>("odometry", 20);
  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  if (options_.use_imu) imu_sub_ = nh_.subscribe("imu", 400, &EkfNode::onImu, this, hints);
  odom_sub_ = nh_.subscribe("odom", 200, &EkfNode::onOdom, this, hints);
  match_sub_ = nh_.subscribe("pose", 20, &EkfNode::onMatch, this, hints);
  initialpose_sub_ = nh_.subscribe("initialpose", 2, &EkfNode::onInitialPose, this);
  if (options_.use_match_status) {
    status_sub_ = nh_.subscribe("status", 20, &EkfNode::onMatchStatus, this, hints);
  }
  setupGnss();
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
  for (ros::Subscriber* sub : {&imu_sub_, &odom_sub_, &match_sub_, &initialpose_sub_, &status_sub_,
                               &gnss_sub_, &index_sub_}) {
    sub->shutdown();
  }
  relocalize_srv_.shutdown();
  diagnostics_.reset();
}

}  // namespace node
}  // namespace gmm_localization
