// Matcher scan path: the bounded scan queue, the worker thread and one scan's processing and
// publication (matcher.h).
#include <cmath>
#include <cstdio>

#include <tf2_eigen/tf2_eigen.h>

#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/matcher.h"
#include "gmm_localization/ros/matcher_outputs.h"

namespace gmm_localization {
namespace node {

namespace {
/// The clock of a match's stage timings [s].
double wallSeconds() { return ros::WallTime::now().toSec(); }
}  // namespace

void Matcher::onScan(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  scan_rate_.tick();
  // Time going backwards (a looping bag): the session forgets the state of the other timeline
  // and drops the waiting scans of the old timeline.
  MatcherSession::Arrival arrival;
  bool recalled = false;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    // No clock yet (sim time before the first /clock): no clock check.
    const ros::Time clock = ros::Time::now();
    arrival =
        session_.onScanArrival(msg->header.stamp.toSec(), clock.isZero() ? NAN : clock.toSec());
    recalled = session_.lastResetRecalled();
  }
  if (!arrival.refused.empty()) {  // a stamp far from the clock: answered, nothing changed
    ROS_WARN_THROTTLE(5.0, "%s: %s", name_.c_str(), arrival.refused.c_str());
    publishSkipped(msg->header.stamp, arrival.refused, 0);
    return;
  }
  if (arrival.timeWentBackwards()) {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++time_resets_;
      time_recalls_ += recalled ? 1 : 0;
    }
    char reason[200];
    std::snprintf(reason, sizeof(reason),
                  recalled ? "time went backwards by %.3f s: matcher state cleared, searching "
                             "around the match remembered at this stamp"
                           : "time went backwards by %.3f s: matcher state cleared, waiting for "
                             "a prior",
                  arrival.backwards_jump_s);
    ROS_WARN("%s: %s", name_.c_str(), reason);
    publishSkipped(msg->header.stamp, reason, 0);
  }
  {
    // A slow match (the first, wide search) leaves a backlog that the tracking matches after it
    // drain; beyond the queue's size the oldest scan goes (counted in the next status).
    std::lock_guard<std::mutex> lock(session_mutex_);
    session_.enqueue(msg);
  }
  queue_cv_.notify_one();
}

template <typename Fn>
void Matcher::answerEvenIfThrows(const sensor_msgs::PointCloud2::ConstPtr& msg, uint32_t dropped,
                                 Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    // Answered all the same: a status names the failure (and the scan counts as processed).
    ROS_ERROR_THROTTLE(5.0, "%s: scan processing failed: %s", name_.c_str(), e.what());
    publishFailure(msg, std::string("scan processing failed: ") + e.what(), dropped);
  } catch (...) {
    ROS_ERROR_THROTTLE(5.0, "%s: scan processing failed (unknown exception)", name_.c_str());
    publishFailure(msg, "scan processing failed: unknown exception", dropped);
  }
}

void Matcher::workerLoop() {
  while (true) {
    sensor_msgs::PointCloud2::ConstPtr msg;
    uint32_t dropped = 0;
    {
      std::unique_lock<std::mutex> lock(session_mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || session_.hasWaiting(); });
      if (stop_) return;
      MatcherSession::Next next = session_.takeNext();
      msg = std::move(next.item);
      dropped = next.dropped_before;
    }
    answerEvenIfThrows(msg, dropped, [&] { processScan(msg, dropped); });
  }
}

void Matcher::globalWorkerLoop() {
  while (true) {
    GlobalJob job;
    {
      std::unique_lock<std::mutex> lock(session_mutex_);
      global_cv_.wait(lock, [this] { return stop_ || global_job_.has_value(); });
      if (stop_) return;
      job = std::move(*global_job_);
      global_job_.reset();
    }
    answerEvenIfThrows(job.msg, job.dropped, [&] {
      runMatch(job.msg, std::move(job.scan), job.start, job.dropped, &global_cancel_);
    });
    std::lock_guard<std::mutex> lock(session_mutex_);
    global_busy_ = false;
  }
}

void Matcher::publishFailure(const sensor_msgs::PointCloud2::ConstPtr& msg,
                             const std::string& reason, uint32_t dropped) {
  try {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++processing_failures_;
    }
    publishSkipped(msg ? msg->header.stamp : ros::Time(), reason, dropped);
  } catch (...) {
    // Publishing itself failed (shutdown): nothing more can be said.
  }
}

bool Matcher::scanToBase(const sensor_msgs::PointCloud2& msg, ScanInput* scan,
                         std::string* reason) {
  auto cloud = fromMsg(msg);
  if (!cloud) {
    *reason = "malformed cloud: " + cloud.error();
    return false;
  }
  if (cloud->points.empty()) {
    *reason = "empty cloud (0 points)";
    return false;
  }
  if (msg.header.stamp.isZero()) {
    *reason = "cloud stamp is zero";
    return false;
  }
  scan->stamp_s = msg.header.stamp.toSec();
  scan->points = std::move(cloud->points);
  scan->time_s = std::move(cloud->time_s);
  scan->intensity = std::move(cloud->intensity);
  scan->time_source = describePointTimes(*cloud);
  scan->time_problem = std::move(cloud->time_problem);
  if (!scan->time_problem.empty() && options_.session.deskew) {
    ROS_WARN_THROTTLE(30.0, "%s: scan not deskewed: %s. Driver fix: %s", name_.c_str(),
                      scan->time_problem.c_str(), pointTimeFixHint());
  }
  if (!msg.header.frame_id.empty() && msg.header.frame_id != options_.base_frame) {
    try {
      const auto t = tf_buffer_.lookupTransform(options_.base_frame, msg.header.frame_id,
                                                msg.header.stamp, ros::Duration(0.05));
      const Eigen::Isometry3f base_T_cloud = tf2::transformToEigen(t).cast<float>();
      for (Eigen::Vector3f& p : scan->points) p = base_T_cloud * p;
    } catch (const tf2::TransformException& e) {
      *reason = "no transform from the cloud frame '" + msg.header.frame_id + "' to '" +
                options_.base_frame + "': " + e.what();
      return false;
    }
  }
  return true;
}

void Matcher::processScan(const sensor_msgs::PointCloud2::ConstPtr& msg, uint32_t dropped) {
  ScanInput scan;
  std::string reason;
  if (!scanToBase(*msg, &scan, &reason)) {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++bad_clouds_;
    }
    ROS_WARN_THROTTLE(5.0, "%s: scan skipped: %s", name_.c_str(), reason.c_str());
    publishSkipped(msg->header.stamp, reason, dropped);
    return;
  }
  MatchStart start;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    start = session_.beginMatch(scan, /*global_available=*/!global_busy_);
    if (start.global()) {
      // The global search goes to its own worker; this one goes on with the next scans.
      global_busy_ = true;
      global_job_ = GlobalJob{msg, std::move(scan), start, dropped};
      global_cancel_ = false;
    }
  }
  if (!start.skip_reason.empty()) {  // answered at once: the global search has the cores
    publishSkipped(msg->header.stamp, start.skip_reason, dropped);
    return;
  }
  if (start.global()) {
    global_cv_.notify_one();
    return;
  }
  runMatch(msg, std::move(scan), start, dropped);
}

void Matcher::runMatch(const sensor_msgs::PointCloud2::ConstPtr& msg, ScanInput scan,
                       const MatchStart& start, uint32_t dropped, const std::atomic<bool>* cancel) {
  std::shared_ptr<const ChunkMap> map;
  // Method fused: the reflectivity layer, or why it cannot be searched (the scan is then
  // answered skipped with that reason by the processor, which gets no second map).
  const bool fused = options_.method.method == MatchMethod::kFused;
  std::shared_ptr<const ChunkMap> reflectivity;
  std::string reflectivity_problem;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    map = map_snapshot_;
    if (fused) {
      reflectivity_problem = reflectivityProblem();
      if (reflectivity_problem.empty()) reflectivity = reflectivity_snapshot_;
    }
  }
  static const ChunkMap kEmpty;
  const bool want_traversal = traversal_pub_.getNumSubscribers() > 0;
  MatchReport report =
      processor_->process(map ? *map : kEmpty, std::move(scan), start.prior, start.twistOrNull(),
                          want_traversal, wallSeconds, reflectivity.get(), cancel);
  if (fused && !reflectivity && report.outcome == MatchOutcome::kSkipped &&
      report.reason.rfind("no reflectivity map", 0) == 0) {
    report.reason = "method fused: " + reflectivity_problem;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++reflectivity_skips_;
  }
  std::string mode;
  {
    // Discards a match begun before time went backwards; else the tracker learns the outcome.
    std::lock_guard<std::mutex> lock(session_mutex_);
    session_.finishMatch(start.epoch, &report);
    mode = priorModeName(session_.tracker().mode());
  }
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    last_mode_ = mode;
  }
  if (!report.accepted()) {
    ROS_WARN_THROTTLE(5.0, "%s: scan at %.3f not matched (%s, prior %s): %s", name_.c_str(),
                      report.stamp_s, matchOutcomeName(report.outcome),
                      priorSourceName(report.prior.source), report.reason.c_str());
  }
  publishOutputs(map ? *map : kEmpty, report, msg->header.stamp, dropped);
  record(report, dropped);
}

void Matcher::publishSkipped(const ros::Time& stamp, const std::string& reason, uint32_t dropped) {
  MatchReport r;
  r.stamp_s = stamp.toSec();
  r.outcome = MatchOutcome::kSkipped;
  r.reason = reason;
  {
    std::lock_guard<std::mutex> lock(session_mutex_);
    r.mode_after = session_.tracker().mode();
  }
  MatchStatus status;
  toStatusMsg(r, options_.map_frame, (ros::Time::now() - stamp).toSec(), dropped, status);
  status.header.stamp = stamp;
  status_pub_.publish(status);
  record(r, dropped);
}

void Matcher::publishOutputs(const ChunkMap& map, MatchReport& report, const ros::Time& stamp,
                             uint32_t dropped) {
  geometry_msgs::PoseWithCovarianceStamped pose;
  if (toMatchPoseMsg(report, options_.map_frame, pose)) {
    pose.header.stamp = stamp;
    pose_pub_.publish(pose);
  } else if (report.accepted()) {
    ROS_ERROR_THROTTLE(5.0, "%s: accepted match with a non-finite pose not published",
                       name_.c_str());
  }
  // The status's latency is the pose's; the labels (its obstacle count) come after it.
  const double latency_s = (ros::Time::now() - stamp).toSec();
  processor_->labelObstacles(map, report, wallSeconds);
  MatchStatus status;
  toStatusMsg(report, options_.map_frame, latency_s, dropped, status);
  status.header.stamp = stamp;
  status_pub_.publish(status);

  // Debug outputs, only while someone listens.
  if (obstacles_pub_.getNumSubscribers() > 0) {
    sensor_msgs::PointCloud2 cloud;
    const bool in_map = options_.obstacles_frame == options_.map_frame;
    if (toObstaclesCloud(report, in_map, cloud)) {
      cloud.header.stamp = stamp;
      cloud.header.frame_id = options_.obstacles_frame;
      obstacles_pub_.publish(cloud);
    }
  }
  if (classified_pub_.getNumSubscribers() > 0) {
    sensor_msgs::PointCloud2 cloud;
    if (toClassifiedCloud(report, options_.classified_max_mahalanobis, cloud)) {
      cloud.header.stamp = stamp;
      cloud.header.frame_id = options_.map_frame;
      classified_pub_.publish(cloud);
    }
  }
  if (traversal_pub_.getNumSubscribers() > 0) {
    sensor_msgs::Image image;
    if (toTraversalImage(report, options_.traversal, image)) {
      image.header.stamp = stamp;
      image.header.frame_id = options_.map_frame;
      traversal_pub_.publish(image);
    }
  }
}

}  // namespace node
}  // namespace gmm_localization
