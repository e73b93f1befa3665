#include "evaluate/evaluate_bag.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>

#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/gnss_conversion.h"

namespace gmm_localization {
namespace eval {
namespace {

constexpr size_t kMaxProblems = 8;

void problem(BagReadStats& s, const std::string& what) {
  ++s.skipped;
  if (s.problems.size() < kMaxProblems) s.problems.push_back(what);
}

PoseStamped2 poseFromOdometry(const nav_msgs::Odometry& m) {
  const auto& q = m.pose.pose.orientation;
  PoseStamped2 p;
  p.t = m.header.stamp.toSec();
  p.x = m.pose.pose.position.x;
  p.y = m.pose.pose.position.y;
  p.z = m.pose.pose.position.z;
  p.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  p.roll = std::atan2(2.0 * (q.w * q.x + q.y * q.z), 1.0 - 2.0 * (q.x * q.x + q.y * q.y));
  p.pitch = std::asin(std::clamp(2.0 * (q.w * q.y - q.z * q.x), -1.0, 1.0));
  return p;
}

bool hasTopic(const rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topic}));
  return view.size() > 0;
}

}  // namespace

Result<LabelledScan> scanFromCloud(const sensor_msgs::PointCloud2& msg,
                                   const std::string& base_frame) {
  using R = Result<LabelledScan>;
  if (msg.header.frame_id != base_frame) {
    return R::failure("cloud in frame '" + msg.header.frame_id + "', expected '" + base_frame +
                      "' (merged clouds only)");
  }
  auto cloud = node::fromMsg(msg);
  if (!cloud) return R::failure("cloud: " + cloud.error());
  LabelledScan s;
  s.scan.stamp_s = msg.header.stamp.toSec();
  s.scan.points = std::move(cloud->points);
  s.scan.time_s = std::move(cloud->time_s);
  s.scan.intensity = std::move(cloud->intensity);
  // As the matcher: the status says how the times were read, or why they were refused.
  s.scan.time_source = node::describePointTimes(*cloud);
  s.scan.time_problem = std::move(cloud->time_problem);
  s.label = std::move(cloud->label);
  return s;
}

namespace {

/// One converted message.
struct Event {
  enum Kind { kScan, kImu, kOdometry, kGroundTruth, kGnss } kind = kScan;
  LabelledScan scan;
  ImuMeasurement imu;
  OdometrySample odometry;
  TwistMeasurement twist;
  PoseStamped2 truth;
  GnssFix gnss;
};

/// Reads and converts messages on its own thread (PointCloud2 parsing is a good part of the
/// cost) into a bounded queue the visiting thread drains in the same order.
class Prefetcher {
 public:
  Prefetcher(rosbag::View& view, const BagTopics& topics, const std::string& gnss_topic)
      : view_(view), topics_(topics), gnss_topic_(gnss_topic) {
    thread_ = std::thread([this]() { run(); });
  }
  ~Prefetcher() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  /// The next event; false at the end of the bag.
  bool next(Event& e) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this]() { return !queue_.empty() || finished_; });
    if (queue_.empty()) return false;
    e = std::move(queue_.front());
    queue_.pop_front();
    if (e.kind == Event::kScan) --scans_queued_;
    changed_.notify_all();
    return true;
  }
  BagReadStats stats() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
  }

 private:
  static constexpr size_t kMaxScans = 3;      // about 3 x 4 MB of points
  static constexpr size_t kMaxEvents = 4000;  // IMU and odometry between them

  void push(Event&& e) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this]() {
      return stop_ || (scans_queued_ < kMaxScans && queue_.size() < kMaxEvents);
    });
    if (e.kind == Event::kScan) ++scans_queued_;
    queue_.push_back(std::move(e));
    changed_.notify_all();
  }
  bool stopped() {
    std::lock_guard<std::mutex> lock(mutex_);
    return stop_;
  }
  void addProblem(const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex_);
    problem(stats_, what);
  }
  void count(uint64_t BagReadStats::*counter, double stamp) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++(stats_.*counter);
    if (!std::isfinite(stamp)) return;
    if (!seen_) stats_.first_stamp_s = stamp;
    seen_ = true;
    stats_.last_stamp_s = std::max(stats_.last_stamp_s, stamp);
  }

  void run() {
    for (const rosbag::MessageInstance& m : view_) {
      if (stopped()) break;
      Event e;
      if (!convert(m, e)) continue;
      push(std::move(e));
    }
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
    changed_.notify_all();
  }

  bool convert(const rosbag::MessageInstance& m, Event& e) {
    const std::string& topic = m.getTopic();
    if (topic == topics_.cloud) {
      const auto msg = m.instantiate<sensor_msgs::PointCloud2>();
      if (!msg) {
        addProblem(topic + ": not a sensor_msgs/PointCloud2");
        return false;
      }
      auto scan = scanFromCloud(*msg, topics_.base_frame);
      if (!scan) {
        addProblem(scan.error());
        return false;
      }
      e.kind = Event::kScan;
      e.scan = std::move(*scan);
      e.scan.record_time_s = m.getTime().toSec();
      count(&BagReadStats::scans, e.scan.scan.stamp_s);
      return true;
    }
    if (topic == topics_.imu) {
      const auto msg = m.instantiate<sensor_msgs::Imu>();
      if (!msg) return false;
      if (!msg->header.frame_id.empty() && msg->header.frame_id != topics_.base_frame) {
        addProblem("IMU in frame '" + msg->header.frame_id + "': only " + topics_.base_frame +
                   " is supported offline");
        return false;
      }
      const auto imu = node::imuFromMsg(*msg);
      if (!imu) {
        addProblem("IMU: " + imu.error());
        return false;
      }
      e.kind = Event::kImu;
      e.imu = *imu;
      count(&BagReadStats::imu, imu->stamp_s);
      return true;
    }
    if (topic == topics_.odom) {
      const auto msg = m.instantiate<nav_msgs::Odometry>();
      if (!msg) return false;
      e.kind = Event::kOdometry;
      e.odometry = node::odometrySampleFromMsg(*msg);
      e.twist = node::twistFromOdometryMsg(*msg);
      count(&BagReadStats::odometry, msg->header.stamp.toSec());
      return true;
    }
    if (!gnss_topic_.empty() && topic == gnss_topic_) {
      const auto msg = m.instantiate<sensor_msgs::NavSatFix>();
      if (!msg) {
        addProblem(topic + ": not a sensor_msgs/NavSatFix");
        return false;
      }
      e.kind = Event::kGnss;
      e.gnss = node::gnssFixFromMsg(*msg);
      count(&BagReadStats::gnss, e.gnss.stamp_s);
      return true;
    }
    if (topic == topics_.ground_truth) {
      const auto msg = m.instantiate<nav_msgs::Odometry>();
      if (!msg) return false;
      e.kind = Event::kGroundTruth;
      e.truth = poseFromOdometry(*msg);
      count(&BagReadStats::ground_truth, e.truth.t);
      return true;
    }
    return false;
  }

  rosbag::View& view_;
  const BagTopics& topics_;
  const std::string gnss_topic_;  ///< empty: not read
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Event> queue_;
  size_t scans_queued_ = 0;
  bool stop_ = false, finished_ = false, seen_ = false;
  BagReadStats stats_;
  std::thread thread_;
};

}  // namespace

Result<BagReadStats> visitLocalizationBag(const std::string& path, const BagTopics& topics,
                                          const BagVisitor& visitor) {
  using R = Result<BagReadStats>;
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    return R::failure("cannot open bag '" + path + "': " + e.what());
  }
  for (const std::string& t : {topics.cloud, topics.ground_truth}) {
    if (!hasTopic(bag, t)) return R::failure("bag '" + path + "' has no topic " + t);
  }
  std::vector<std::string> wanted;
  if (visitor.scan) wanted.push_back(topics.cloud);
  if (visitor.imu) wanted.push_back(topics.imu);
  if (visitor.odometry) wanted.push_back(topics.odom);
  if (visitor.ground_truth) wanted.push_back(topics.ground_truth);
  if (visitor.gnss) {
    if (!hasTopic(bag, visitor.gnss_topic)) {
      return R::failure("bag '" + path + "' has no GNSS fixes on " + visitor.gnss_topic +
                        " (simulate --gnss realistic writes them)");
    }
    wanted.push_back(visitor.gnss_topic);
  }
  rosbag::View view(bag, rosbag::TopicQuery(wanted));
  Prefetcher reader(view, topics, visitor.gnss ? visitor.gnss_topic : std::string());
  Event e;
  while (reader.next(e)) {
    if (visitor.done && visitor.done()) break;
    switch (e.kind) {
      case Event::kScan:
        visitor.scan(std::move(e.scan));
        break;
      case Event::kImu:
        visitor.imu(e.imu);
        break;
      case Event::kOdometry:
        visitor.odometry(e.odometry, e.twist);
        break;
      case Event::kGroundTruth:
        visitor.ground_truth(e.truth);
        break;
      case Event::kGnss:
        visitor.gnss(e.gnss);
        break;
    }
  }
  return reader.stats();
}

Result<Trajectory> readTrajectory(const std::string& path, const std::string& topic) {
  using R = Result<Trajectory>;
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    return R::failure("cannot open bag '" + path + "': " + e.what());
  }
  // Stamps may be recorded out of order: sort before building the trajectory.
  std::vector<PoseStamped2> poses;
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topic}));
  for (const rosbag::MessageInstance& m : view) {
    const auto msg = m.instantiate<nav_msgs::Odometry>();
    if (msg) poses.push_back(poseFromOdometry(*msg));
  }
  if (poses.empty()) return R::failure("bag '" + path + "' has no nav_msgs/Odometry on " + topic);
  std::stable_sort(poses.begin(), poses.end(),
                   [](const PoseStamped2& a, const PoseStamped2& b) { return a.t < b.t; });
  Trajectory t;
  for (const PoseStamped2& p : poses) t.add(p);
  return t;
}

size_t countMessages(const std::string& path, const std::string& topic) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException&) {
    return 0;
  }
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topic}));
  return view.size();
}

double medianScanRecordDelay(const std::string& path, const std::string& topic, size_t max_scans) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException&) {
    return 0.0;
  }
  std::vector<double> delays;
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topic}));
  for (const rosbag::MessageInstance& m : view) {
    if (delays.size() >= max_scans) break;
    // Only the header is needed, but PointCloud2 has no cheaper accessor in rosbag.
    const auto msg = m.instantiate<sensor_msgs::PointCloud2>();
    if (msg) delays.push_back(m.getTime().toSec() - msg->header.stamp.toSec());
  }
  if (delays.empty()) return 0.0;
  std::nth_element(delays.begin(), delays.begin() + delays.size() / 2, delays.end());
  return delays[delays.size() / 2];
}

}  // namespace eval
}  // namespace gmm_localization
