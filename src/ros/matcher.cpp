// Matcher set-up and tear-down (see matcher.h).
#include "gmm_localization/ros/matcher.h"

#include <algorithm>

#include <boost/function.hpp>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/Image.h>

#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

MatcherSession makeMatcherSession(const MatcherOptions& options) {
  MatcherSession session(options.session, options.policy);
  if (options.initial_pose_enabled) {
    const WindowExtent window = configuredPoseWindow(options);
    session.setConfiguredPose(options.initial_pose, options.initial_pose_z_known, &window);
  }
  return session;
}

Matcher::Matcher(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : name_(name),
      nh_(nh),
      pnh_(pnh),
      options_(loadNodeletOptions(pnh, name, loadMatcherOptions)),
      tf_listener_(tf_buffer_),
      session_(makeMatcherSession(options_)),
      scan_rate_(0.5 * options_.expected_scan_rate_hz, 2.0 * options_.expected_scan_rate_hz),
      acquisition_(
          AcquisitionWatchOptions{acquisitionWarnAfter(options_.policy.relocalization), 15.0}) {
  // The obstacle labels wait until the pose is out (publishOutputs).
  auto processor =
      MatchProcessor::create(options_.registration, options_.policy, options_.method, true);
  if (!processor) throw ConfigError(processor.error());
  processor_ = std::make_unique<MatchProcessor>(std::move(processor).value());

  pose_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 10);
  status_pub_ = nh_.advertise<MatchStatus>("status", 10);
  obstacles_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("obstacles", 1);
  classified_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("scan_classified", 1);
  traversal_pub_ = nh_.advertise<sensor_msgs::Image>("search_traversal", 1);

  scan_topic_ = nh_.resolveName("velodyne_points");
  scans_input_ = inputs_.add(scan_topic_);
  matches_input_ = inputs_.add("accepted matches", /*watch_silence=*/false);
  inputs_.start(ros::WallTime::now().toSec());

  const ros::TransportHints hints = ros::TransportHints().tcpNoDelay();
  // A subscriber queue deeper than the session's: every scan reaches onScan, so a scan dropped
  // under load is dropped (and counted) by the session. Each scan is seen by the silence
  // watchdog and the stamp check first (onScan counts it in the rate).
  const boost::function<void(const sensor_msgs::PointCloud2::ConstPtr&)> on_scan =
      [this](const sensor_msgs::PointCloud2::ConstPtr& msg) {
        scan_rate_.stamp(msg->header.stamp);
        {
          std::lock_guard<std::mutex> lock(stats_mutex_);
          inputs_.heard(scans_input_, ros::WallTime::now().toSec());
        }
        onScan(msg);
      };
  scan_sub_ = nh_.subscribe<sensor_msgs::PointCloud2>(
      "velodyne_points",
      static_cast<uint32_t>(
          std::max(options_.scan_subscriber_queue_size, options_.session.scan_queue_size + 1)),
      on_scan, ros::VoidConstPtr(), hints);
  odom_sub_ = nh_.subscribe("odom", 200, &Matcher::onOdom, this, hints);
  posterior_sub_ = nh_.subscribe("odometry", 20, &Matcher::onPosterior, this, hints);
  initialpose_sub_ = nh_.subscribe("initialpose", 2, &Matcher::onInitialPose, this);
  chunk_sub_ = nh_.subscribe("map_chunks", 512, &Matcher::onChunk, this);
  index_sub_ = nh_.subscribe("map_index", 8, &Matcher::onIndex, this);
  if (options_.method.method == MatchMethod::kFused) {
    // The second layer, from a second map server (localization.launch method:=fused).
    reflectivity_topic_ = nh_.resolveName("reflectivity/map_index");
    reflectivity_chunk_sub_ =
        nh_.subscribe("reflectivity/map_chunks", 512, &Matcher::onReflectivityChunk, this);
    reflectivity_index_sub_ =
        nh_.subscribe("reflectivity/map_index", 8, &Matcher::onReflectivityIndex, this);
  }
  global_srv_ = nh_.advertiseService("global_localization", &Matcher::onGlobalLocalization, this);

  setupDiagnostics();
  worker_ = std::thread([this] { workerLoop(); });
  global_worker_ = std::thread([this] { globalWorkerLoop(); });
  ROS_INFO(
      "%s: matching scans in frame '%s' against map '%s'%s%s", name_.c_str(),
      options_.base_frame.c_str(), options_.map_frame.c_str(),
      options_.initial_pose_enabled ? " from the configured initial pose" : "",
      reflectivity_topic_.empty()
          ? ""
          : (" (method fused: the reflectivity layer from " + reflectivity_topic_ + ")").c_str());
}

Matcher::~Matcher() {
  // No callback or diagnostics task may run while the members go away.
  for (ros::Subscriber* sub :
       {&scan_sub_, &odom_sub_, &posterior_sub_, &initialpose_sub_, &chunk_sub_, &index_sub_,
        &reflectivity_chunk_sub_, &reflectivity_index_sub_}) {
    sub->shutdown();
  }
  global_srv_.shutdown();
  diagnostics_.reset();
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_all();
  global_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (global_worker_.joinable()) global_worker_.join();
}

}  // namespace node
}  // namespace gmm_localization
