// Matcher inputs other than scans: INS odometry, EKF posterior, initial pose, map (matcher.h).
#include <cmath>
#include <optional>
#include <string>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/raster/window_coverage.h"
#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/matcher.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {

void Matcher::onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
  if (!msg->child_frame_id.empty() && msg->child_frame_id != options_.base_frame) {
    ROS_WARN_THROTTLE(10.0,
                      "%s: INS odometry child frame '%s' is not '%s'; its twist is used "
                      "as if it were",
                      name_.c_str(), msg->child_frame_id.c_str(), options_.base_frame.c_str());
  }
  const OdometrySample sample = odometrySampleFromMsg(*msg);
  OdometryBuffer::AddResult r;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    r = session_.addOdometry(sample);
  }
  if (r == OdometryBuffer::AddResult::kTimeWentBackwards) {
    ROS_WARN_THROTTLE(2.0, "%s: INS odometry went back in time: its buffer restarted",
                      name_.c_str());
  } else if (r == OdometryBuffer::AddResult::kDroppedOutOfOrder) {
    ROS_WARN_THROTTLE(10.0, "%s: INS odometry sample out of order or not finite: ignored",
                      name_.c_str());
  }
}

void Matcher::onPosterior(const nav_msgs::Odometry::ConstPtr& msg) {
  if (msg->header.frame_id != options_.map_frame) {
    ROS_WARN_THROTTLE(10.0, "%s: EKF odometry in frame '%s', expected '%s': ignored", name_.c_str(),
                      msg->header.frame_id.c_str(), options_.map_frame.c_str());
    return;
  }
  std::lock_guard<std::mutex> lock(session_mutex_);
  session_.setPosterior(posteriorFromOdometryMsg(*msg));  // ignores non-finite estimates
}

void Matcher::onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  const auto pose = initialPoseInMap(*msg, options_.map_frame, tf_buffer_);
  if (!pose) {
    ROS_WARN("%s: initial pose ignored: %s", name_.c_str(), pose.error().c_str());
    return;
  }
  // rviz's "2D Pose Estimate" gives x, y, yaw (z = 0): complete z, roll, pitch.
  const double stamp = msg->header.stamp.isZero() ? NAN : pose->stamp_s;
  bool z_known = false;
  Pose6 full;
  // The message's (x, y, yaw) covariance: a coarse fix (large sigma) widens the search up to
  // the global window.
  const auto& c = msg->pose.covariance;
  Eigen::Matrix3d cov_xyh;
  cov_xyh << c[0], c[1], c[5], c[6], c[7], c[11], c[30], c[31], c[35];
  WindowExtent window;
  bool cancelled = false;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    full =
        session_.setInitialPose(pose->pose, stamp, /*z_known=*/false, &z_known, &cov_xyh, &window);
    // A global search around the old estimate is no longer wanted: the cores go to this pose.
    if (global_busy_) {
      global_cancel_ = true;
      cancelled = true;
    }
  }
  if (cancelled) {
    ROS_INFO("%s: the running global search around the previous estimate is cancelled",
             name_.c_str());
  }
  ROS_INFO("%s: initial pose x %.2f y %.2f yaw %.3f (z %.2f %s): searching +-%.1f m, +-%.0f deg",
           name_.c_str(), full.x, full.y, full.yaw, full.z,
           z_known ? "from the posterior" : "unknown", window.half_x_m,
           window.half_heading_rad * 180.0 / M_PI);
}

bool Matcher::onGlobalLocalization(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  const LocalizationPolicyOptions& p = options_.policy;
  const double half = p.window.global_max_half_xy_m;
  // The estimate the search will be centred on: the prior at the newest INS odometry.
  std::optional<Pose6> centre;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    if (session_.tracker().mode() != PriorMode::kNoPrior) {
      const double t = session_.odometry().empty() ? session_.tracker().posterior().stamp_s
                                                   : session_.odometry().newest().stamp_s;
      const Prior prior = session_.tracker().priorAt(t, &session_.odometry());
      if (prior.valid()) centre = prior.pose;
    }
  }
  // Outside the map the server holds there is nothing to search; a window larger than it is
  // searched over the loaded part (said in the answer).
  std::string refused, coverage;
  if (centre) {
    std::lock_guard<std::mutex> lock(map_mutex_);
    static const ChunkMap kEmpty;
    const WindowCoverage c =
        windowCoverage(map_snapshot_ ? *map_snapshot_ : kEmpty, centre->x, centre->y, half, half);
    coverage = describeWindowCoverage(c, centre->x, centre->y, half);
    if (!c.centre_loaded) {
      refused = "the current estimate is outside the loaded map: " + coverage +
                "; give a pose on the map on /initialpose";
    }
  }
  if (refused.empty()) {
    std::lock_guard<std::mutex> lock(session_mutex_);
    refused = session_.requestGlobalSearch();
  }
  res.success = refused.empty();
  res.message = res.success ? "global search armed: +-" + std::to_string(static_cast<int>(half)) +
                                  " m and +-" +
                                  std::to_string(static_cast<int>(std::lround(
                                      p.window.global_max_half_heading_rad * 180.0 / M_PI))) +
                                  " deg around the current estimate from the next scan; " + coverage
                            : "global search refused: " + refused;
  ROS_INFO("%s: %s", name_.c_str(), res.message.c_str());
  return true;
}

void Matcher::onChunk(const ros::MessageEvent<const RasterChunk>& event) {
  const RasterChunk::ConstPtr msg = event.getConstMessage();
  std::string error;
  std::lock_guard<std::mutex> lock(map_mutex_);
  const auto verdict = map_client_.onChunk(event, &error);
  if (verdict == MapServerClient::ChunkVerdict::kInvalid) {
    ROS_WARN_THROTTLE(5.0, "%s: chunk (%d, %d) rejected: %s", name_.c_str(), msg->chunk_x,
                      msg->chunk_y, error.c_str());
    return;
  }
  if (verdict == MapServerClient::ChunkVerdict::kAdded && map_client_.hasIndex()) {
    // Copy-on-write: the worker keeps searching its own snapshot (chunks are shared).
    map_snapshot_ = std::make_shared<const ChunkMap>(map_client_.chunks());
  }
}

void Matcher::onIndex(const ros::MessageEvent<const MapIndex>& event) {
  const MapIndex::ConstPtr msg = event.getConstMessage();
  std::lock_guard<std::mutex> lock(map_mutex_);
  const uint64_t previous = map_client_.mapVersion();
  std::string rejected;
  const size_t dropped = map_client_.onIndex(event, &rejected);
  if (!rejected.empty()) {
    ROS_WARN_THROTTLE(5.0, "%s: map index ignored (the current map stays in use): %s",
                      name_.c_str(), rejected.c_str());
  } else if (map_client_.mapVersion() != previous) {
    ROS_INFO("%s: map version %lu ('%s'), %zu chunks listed", name_.c_str(),
             static_cast<unsigned long>(map_client_.mapVersion()), msg->map_directory.c_str(),
             msg->chunk_x.size());
  } else if (dropped > 0) {
    ROS_DEBUG("%s: %zu chunks evicted by the map index", name_.c_str(), dropped);
  }
  map_snapshot_ = std::make_shared<const ChunkMap>(map_client_.chunks());
  if (options_.method.method == MatchMethod::kFused) checkLayers();
}

}  // namespace node
}  // namespace gmm_localization
