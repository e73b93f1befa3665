#include "gmm_localization/ros/cloud_merger.h"

#include <algorithm>

#include <boost/make_shared.hpp>

#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/cloud_merger_assembly.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {

CloudMerger::CloudMerger(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : nh_(nh),
      pnh_(pnh),
      name_(name),
      options_(loadNodeletOptions(pnh, name, loadCloudMergerOptions)),
      sync_(options_.sync),
      output_rate_(0.5 * options_.expected_rate_hz, 1.5 * options_.expected_rate_hz) {
  for (const std::string& topic : options_.input_topics) {
    inputs_.push_back(std::make_unique<Input>(topic, options_.expected_rate_hz));
  }
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  pub_ = nh_.advertise<sensor_msgs::PointCloud2>("velodyne_points", 2);
  for (size_t i = 0; i < inputs_.size(); ++i) {
    boost::function<void(const sensor_msgs::PointCloud2::ConstPtr&)> cb =
        [this, i](const sensor_msgs::PointCloud2::ConstPtr& msg) { onCloud(msg, i); };
    subs_.push_back(nh_.subscribe<sensor_msgs::PointCloud2>(
        options_.input_topics[i], static_cast<uint32_t>(options_.input_queue_size), cb,
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
  }
  const double poll_s = std::min(0.01, options_.sync.max_wait_s / 4.0);
  poll_timer_ = nh_.createWallTimer(ros::WallDuration(poll_s),
                                    [this](const ros::WallTimerEvent&) { onPoll(); });
  setUpDiagnostics();
  std::string topics;
  for (const std::string& t : options_.input_topics) {
    topics += (topics.empty() ? "" : ", ") + nh_.resolveName(t);
  }
  ROS_INFO("%s: merging %s into %s (%s), max wait %.3f s, stamp spread < %.3f s", name_.c_str(),
           topics.c_str(), nh_.resolveName("velodyne_points").c_str(),
           options_.output_frame.c_str(), options_.sync.max_wait_s,
           options_.sync.max_stamp_spread_s);
}

CloudMerger::~CloudMerger() {
  poll_timer_.stop();
  subs_.clear();
  diagnostics_.reset();  // its tasks read members destroyed before it
}

void CloudMerger::warn(Input& input, const std::string& what) {
  constexpr double kPeriodS = 5.0;
  const double now = wallNow();
  if (now - input.last_log_s < kPeriodS) return;
  input.last_log_s = now;
  ROS_WARN("%s: %s: %s", name_.c_str(), input.topic.c_str(), what.c_str());
}

bool CloudMerger::extrinsic(Input& input, const std::string& frame, Eigen::Isometry3d& T) {
  if (frame == options_.output_frame) {
    T = Eigen::Isometry3d::Identity();
    return true;
  }
  std::string error;
  try {
    const auto t = tf_buffer_.lookupTransform(options_.output_frame, frame, ros::Time(0));
    T = fromMsg(t.transform);
    if (T.matrix().allFinite()) {
      input.extrinsic = T;
      input.extrinsic_frame = frame;
      return true;
    }
    error = "TF gives a non-finite transform";
  } catch (const tf2::TransformException& e) {
    error = e.what();
  }
  // Static extrinsics: the last transform found stays valid (tf2 drops /tf_static on a jump
  // back in time, and a bag loop republishes it only at its start).
  if (input.extrinsic && input.extrinsic_frame == frame) {
    T = *input.extrinsic;
    return true;
  }
  input.last_error = "no transform " + options_.output_frame + " <- " + frame + ": " + error;
  input.last_error_time_s = wallNow();
  warn(input, "cloud skipped: " + input.last_error);
  return false;
}

void CloudMerger::onCloud(const sensor_msgs::PointCloud2::ConstPtr& msg, size_t sensor) {
  const double arrival_s = wallNow();
  Input& input = *inputs_[sensor];
  input.rate.tick();
  input.rate.stamp(msg->header.stamp);
  auto data = fromMsg(*msg);
  std::lock_guard<std::mutex> lock(mutex_);
  ++input.received;
  input.frame = msg->header.frame_id;
  if (!data || msg->header.frame_id.empty()) {
    ++input.malformed;
    input.last_error = "malformed cloud: " + (data ? std::string("empty frame_id") : data.error());
    input.last_error_time_s = arrival_s;
    warn(input, "cloud dropped: " + input.last_error);
    return;
  }
  Eigen::Isometry3d T;
  if (!extrinsic(input, msg->header.frame_id, T)) {
    ++input.no_tf;
    return;
  }
  auto cloud = std::make_shared<CloudData>();
  input.nonfinite_points += transformCloud(*data, T, *cloud);

  MergeInput in;
  in.sensor = sensor;
  in.stamp_ns = static_cast<int64_t>(msg->header.stamp.toNSec());
  in.arrival_s = arrival_s;
  in.cloud = std::move(cloud);
  std::vector<MergeCycle> closed;
  const uint64_t resets = sync_.counters().resets;
  switch (sync_.add(std::move(in), closed)) {
    case MergeVerdict::kLate:
      ++input.late;
      warn(input, "late cloud dropped (stamped before the last output)");
      break;
    case MergeVerdict::kOutOfWindow:
      ++input.out_of_window;
      warn(input, "cloud dropped: outside the current set's stamp window");
      break;
    default:
      break;
  }
  if (sync_.counters().resets != resets) {
    ROS_WARN("%s: time went backwards on %s (by more than %.2f s): merger state reset",
             name_.c_str(), input.topic.c_str(), options_.sync.backwards_reset_s);
  }
  for (const MergeCycle& c : closed) publish(c);
}

void CloudMerger::onPoll() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto cycle = sync_.poll(wallNow())) publish(*cycle);
}

void CloudMerger::publish(const MergeCycle& cycle) {
  // Called with mutex_ held.
  std::vector<UntimedInput> untimed;
  const CloudData merged = mergeCycle(cycle, &untimed);
  auto msg = boost::make_shared<sensor_msgs::PointCloud2>();
  toMsg(merged, *msg);
  msg->header.stamp.fromNSec(static_cast<uint64_t>(cycle.stamp_ns));
  msg->header.frame_id = options_.output_frame;
  msg->is_dense = true;  // non-finite points were dropped
  pub_.publish(sensor_msgs::PointCloud2::ConstPtr(msg));

  const double now_s = wallNow();
  output_rate_.tick();
  ++published_;
  last_points_ = merged.points.size();
  last_latency_ms_ = (now_s - cycle.first_arrival_s) * 1e3;
  sum_latency_ms_ += last_latency_ms_;
  max_latency_ms_ = std::max(max_latency_ms_, last_latency_ms_);
  if (!untimed.empty()) ++untimed_scans_;
  for (const UntimedInput& u : untimed) {
    if (u.sensor >= inputs_.size()) continue;
    Input& input = *inputs_[u.sensor];
    ++input.untimed;
    input.last_time_problem = u.reason;
    input.last_time_problem_s = now_s;
    std::string what = u.reason +
                       "; its points carry NaN times in the merged scan, which is therefore "
                       "not deskewed";
    if (u.refused) what += ". Driver fix: " + std::string(pointTimeFixHint());
    warn(input, what);
  }
  if (!cycle.missing.empty()) {
    last_missing_ = cycle.missing;
    last_missing_time_s_ = now_s;
    std::string names;
    for (size_t i : cycle.missing) names += (names.empty() ? "" : ", ") + inputs_[i]->topic;
    ROS_WARN_THROTTLE(
        5.0, "%s: published a scan without %s (%s)", name_.c_str(), names.c_str(),
        cycle.closed == MergeCycle::Closed::kTimeout ? "waited max_wait_s" : "the next set began");
  }
}

}  // namespace node
}  // namespace gmm_localization
