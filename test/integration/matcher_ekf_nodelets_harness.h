#pragma once
// Test harness of the matcher + ekf rostest (matcher_ekf_nodelets.test): it plays a recorded
// drive's part on sim time - /clock, the map (index + chunks of a synthetic street world,
// rasterized in-process), INS odometry + TF odom -> base_link, a level IMU and scans from a
// known, fixed pose - and records what the nodelets publish.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "../unit/support/synthetic_world.h"
#include "gmm_localization/MapIndex.h"
#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "gmm_localization/ros/chunk_conversion.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/map_server_client.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace testing_harness {

constexpr double kStartS = 1000.0;  // sim time at start [s]

/// The vehicle's true pose (fixed): on the street at x = 0 of SyntheticWorld(42, 40).
inline Pose6 truth() {
  Pose6 p;
  p.x = 2.0;
  p.y = -20.0;
  p.z = 0.01 * p.x + 0.005 * p.y;  // SyntheticWorld::ground
  p.yaw = M_PI / 2 + 0.1;
  return p;
}

inline double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

inline bool finite(const geometry_msgs::Pose& p) {
  return isFinite(p) && std::isfinite(p.orientation.x) && std::isfinite(p.orientation.w);
}

template <size_t N>
bool finite(const boost::array<double, N>& a) {
  for (double v : a) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

class Harness {
 public:
  Harness() : tf_listener_(tf_buffer_) {
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
    scan_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 5);
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>("/odom", 50);
    imu_pub_ = nh_.advertise<sensor_msgs::Imu>("/imu", 50);
    index_pub_ = nh_.advertise<MapIndex>("/map_index", 1, true);
    chunk_pub_ = nh_.advertise<RasterChunk>("/map_chunks", 256);
    pose_sub_ = nh_.subscribe("/pose", 50, &Harness::onPose, this);
    status_sub_ = nh_.subscribe("/status", 200, &Harness::onStatus, this);
    odometry_sub_ = nh_.subscribe("/odometry", 200, &Harness::onOdometry, this);
    diagnostics_sub_ = nh_.subscribe("/diagnostics", 50, &Harness::onDiagnostics, this);
    diagnostics_agg_sub_ =
        nh_.subscribe("/diagnostics_agg", 10, &Harness::onAggregatedDiagnostics, this);
    rosout_sub_ = nh_.subscribe("/rosout", 500, &Harness::onLog, this);
    buildWorld();
    thread_ = std::thread([this] { run(); });
  }
  ~Harness() {
    stop_ = true;
    thread_.join();
    // Before the members the callbacks write: shutdown() waits for a callback in progress.
    for (ros::Subscriber* s : {&pose_sub_, &status_sub_, &odometry_sub_, &diagnostics_sub_,
                               &diagnostics_agg_sub_, &rosout_sub_}) {
      s->shutdown();
    }
  }

  /// Sim time now (the clock this node publishes).
  double simNow() const {
    return kStartS + (ros::WallTime::now() - wall_start_).toSec() - offset_.load();
  }
  /// The clock and every stamp jump back by seconds (a looping bag).
  void loop(double seconds) { offset_ = offset_.load() + seconds; }
  void setStreaming(bool on) { streaming_ = on; }

  /// Publishes the map once the matcher listens (index latched, then every chunk).
  bool publishMap(double timeout_s) {
    if (!waitFor([&] { return chunk_pub_.getNumSubscribers() > 0; }, timeout_s)) return false;
    MapIndex index;
    index.header.stamp.fromSec(simNow());
    index.header.frame_id = "map";
    index.map_directory = "synthetic";
    index.map_version = 7;
    toMsg(chunks_.geometry(), chunks_.options(), index);
    for (const auto& kv : chunks_.chunks()) {
      index.chunk_x.push_back(kv.first.x);
      index.chunk_y.push_back(kv.first.y);
    }
    index_pub_.publish(index);
    for (const auto& kv : chunks_.chunks()) {
      auto msg = boost::make_shared<RasterChunk>();
      toMsg(*kv.second, index.map_version, "map", index.header.stamp + ros::Duration(0.001), *msg);
      chunk_pub_.publish(msg);
    }
    return true;
  }

  /// A valid scan message of the truth pose at sim time t.
  sensor_msgs::PointCloud2 scanAt(double t) const {
    sensor_msgs::PointCloud2 msg = scan_msg_;
    msg.header.stamp.fromSec(t);
    return msg;
  }
  void publishScan(const sensor_msgs::PointCloud2& msg) { scan_pub_.publish(msg); }

  static bool waitFor(const std::function<bool()>& done, double timeout_s) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok() && ros::WallTime::now() < end) {
      if (done()) return true;
      ros::WallDuration(0.01).sleep();
    }
    return done();
  }

  template <typename F>
  auto locked(F f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f();
  }

  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
  std::vector<MatchStatus> statuses_;
  std::vector<nav_msgs::Odometry> odometry_;
  std::set<std::string> diagnostic_names_;
  /// Every status seen, with the wall time it arrived [s].
  std::vector<std::pair<double, diagnostic_msgs::DiagnosticStatus>> diagnostics_;
  std::vector<diagnostic_msgs::DiagnosticStatus> aggregated_;  ///< the last /diagnostics_agg
  std::vector<std::pair<double, rosgraph_msgs::Log>> logs_;    ///< /rosout, with wall time [s]
  bool non_finite_ = false;
  std::string non_finite_what_;
  tf2_ros::Buffer tf_buffer_;

 private:
  void buildWorld() {
    const testing::SyntheticWorld world(42, 40.0);
    MapGeometry g;
    g.resolution_m = 0.2;
    g.tile_size_cells = 128;
    const GmmMap gmm = world.buildMap(g, 1);
    RasterOptions o;
    chunks_ = ChunkMap(g, o);
    for (int cy = -3; cy <= 2; ++cy) {
      for (int cx = -3; cx <= 2; ++cx) chunks_.insert(rasterizeChunk(gmm, {cx, cy}, o).value());
    }
    CloudData cloud;
    cloud.points = world.scan(truth(), 30.0, 0.3, 0.02, 11);
    for (size_t i = 0; i < cloud.points.size(); ++i) {
      cloud.time_s.push_back(0.1f * static_cast<float>(i) / cloud.points.size());
      cloud.intensity.push_back(50.0f);
    }
    toMsg(cloud, scan_msg_);
    scan_msg_.header.frame_id = "base_link";
  }

  void run() {
    tf2_ros::TransformBroadcaster tf;
    for (uint64_t k = 0; !stop_ && ros::ok(); ++k) {
      const double t = simNow();
      rosgraph_msgs::Clock clock;
      clock.clock.fromSec(t);
      clock_pub_.publish(clock);
      ros::Time stamp;
      stamp.fromSec(t);
      if (k % 2 == 0) {  // IMU 100 Hz, level and still; covariances unknown (defaults)
        sensor_msgs::Imu imu;
        imu.header.stamp = stamp;
        imu.header.frame_id = "base_link";
        imu.orientation.w = 1.0;
        imu.linear_acceleration.z = 9.80665;
        imu_pub_.publish(imu);
      }
      if (k % 4 == 0) {  // INS 50 Hz: the vehicle stands at the odom origin
        nav_msgs::Odometry odom;
        odom.header.stamp = stamp;
        odom.header.frame_id = "odom";
        odom.child_frame_id = "base_link";
        odom.pose.pose.orientation.w = 1.0;
        odom_pub_.publish(odom);
        geometry_msgs::TransformStamped t_ob;
        t_ob.header = odom.header;
        t_ob.child_frame_id = "base_link";
        t_ob.transform.rotation.w = 1.0;
        tf.sendTransform(t_ob);
      }
      if (k % 40 == 20 && streaming_) publishScan(scanAt(t));  // 5 Hz
      ros::WallDuration(0.005).sleep();
    }
  }

  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_.push_back(*m);
    if (!finite(m->pose.pose) || !finite(m->pose.covariance)) flag("pose");
  }
  void onStatus(const MatchStatus::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.push_back(*m);
    if (!finite(m->pose.pose) || !finite(m->pose.covariance) || !std::isfinite(m->total_ms) ||
        !std::isfinite(m->log_likelihood_per_point)) {
      flag("status");
    }
  }
  void onOdometry(const nav_msgs::Odometry::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    odometry_.push_back(*m);
    if (!finite(m->pose.pose) || !finite(m->pose.covariance) || !finite(m->twist.covariance) ||
        !std::isfinite(m->twist.twist.linear.x)) {
      flag("odometry");
    }
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double now = ros::WallTime::now().toSec();
    for (const auto& st : m->status) {
      diagnostic_names_.insert(st.name);
      diagnostics_.emplace_back(now, st);
    }
  }
  void onAggregatedDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    aggregated_ = m->status;
  }
  void onLog(const rosgraph_msgs::Log::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.emplace_back(ros::WallTime::now().toSec(), *m);
  }
  void flag(const char* what) {
    non_finite_ = true;
    non_finite_what_ = what;
  }

  ros::NodeHandle nh_;
  tf2_ros::TransformListener tf_listener_;
  ros::Publisher clock_pub_, scan_pub_, odom_pub_, imu_pub_, index_pub_, chunk_pub_;
  ros::Subscriber pose_sub_, status_sub_, odometry_sub_, diagnostics_sub_, diagnostics_agg_sub_;
  ros::Subscriber rosout_sub_;
  ChunkMap chunks_;
  sensor_msgs::PointCloud2 scan_msg_;
  ros::WallTime wall_start_ = ros::WallTime::now();
  std::atomic<double> offset_{0.0};
  std::atomic<bool> streaming_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::mutex mutex_;
};

}  // namespace testing_harness
}  // namespace node
}  // namespace gmm_localization
