#pragma once
// A rosbag player for the robustness rostest (vehicle_robustness_test.cpp): plays the fixture's
// drive on sim time (/clock = bag time, rate 1) like `rosbag play -(-)clock`, and injects faults
// by bag time: IMU dropouts, INS dropouts (odometry and TF odom -> base_link), scans in a frame
// TF does not know. It can hold the clock (a stopped recording) and resume.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace vehicle_test {

/// A fault over bag times [from_s, to_s) relative to the bag's first message.
struct FaultWindow {
  double from_s = 0.0, to_s = 0.0;
  bool contains(double rel_s) const { return rel_s >= from_s && rel_s < to_s; }
};

struct Faults {
  std::vector<FaultWindow> no_imu;         ///< /imu/data not published
  std::vector<FaultWindow> no_ins;         ///< /ins/odom and /tf (odom -> base_link) not published
  std::vector<FaultWindow> unknown_frame;  ///< scans (by stamp) in a frame without TF
  static bool any(const std::vector<FaultWindow>& w, double rel_s) {
    for (const FaultWindow& f : w) {
      if (f.contains(rel_s)) return true;
    }
    return false;
  }
};

class FaultyPlayer {
 public:
  static constexpr const char* kUnknownFrame = "velodyne_uncalibrated";

  FaultyPlayer(ros::NodeHandle& nh, const std::string& bag_path, Faults faults)
      : faults_(std::move(faults)) {
    bag_.open(bag_path, rosbag::bagmode::Read);
    rosbag::View gt(bag_, rosbag::TopicQuery(std::vector<std::string>{"/ground_truth/odom"}));
    for (const rosbag::MessageInstance& m : gt) {
      const auto odom = m.instantiate<nav_msgs::Odometry>();
      if (odom) truth_.add(odom->header.stamp.toSec(), toPose(odom->pose.pose));
    }
    rosbag::View all(bag_);
    start_ = all.getBeginTime();
    end_ = all.getEndTime();
    clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    scan_pub_ = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 2);
    odom_pub_ = nh.advertise<nav_msgs::Odometry>("/ins/odom", 100);
    imu_pub_ = nh.advertise<sensor_msgs::Imu>("/imu/data", 200);
    tf_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
    tf_static_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
  }
  ~FaultyPlayer() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

  const Truth& truth() const { return truth_; }
  ros::Time start() const { return start_; }
  ros::Time end() const { return end_; }
  /// Bag time of the last published message [s since the start].
  double elapsed() const { return elapsed_.load(); }
  bool finished() const { return finished_.load(); }

  /// Starts playing (rate 1 from now).
  void play() {
    thread_ = std::thread([this] { run(); });
  }
  /// Holds the clock where it is / lets it run again.
  void hold(bool on) { held_ = on; }
  /// The last scan published (null before the first), as it went out.
  sensor_msgs::PointCloud2ConstPtr lastScan() const {
    std::lock_guard<std::mutex> lock(scan_mutex_);
    return last_scan_;
  }
  /// Before play(): publishes the bag's start time on /clock (nodes on sim time wait for it).
  void publishStartClock() { publishClock(start_); }

 private:
  void publishClock(const ros::Time& t) {
    rosgraph_msgs::Clock c;
    c.clock = t;
    clock_pub_.publish(c);
  }

  void run() {
    rosbag::View view(
        bag_, rosbag::TopicQuery(std::vector<std::string>{"/velodyne_points", "/ins/odom",
                                                          "/imu/data", "/tf", "/tf_static"}));
    ros::WallTime wall_start = ros::WallTime::now();
    for (const rosbag::MessageInstance& m : view) {
      const double rel = (m.getTime() - start_).toSec();
      // Wait for the message's time; a hold shifts the whole remaining timeline.
      while (!stop_ && ros::ok()) {
        if (held_) {
          const ros::WallTime hold_start = ros::WallTime::now();
          while (held_ && !stop_ && ros::ok()) ros::WallDuration(0.01).sleep();
          wall_start += ros::WallTime::now() - hold_start;
          continue;
        }
        const double wait = rel - (ros::WallTime::now() - wall_start).toSec();
        if (wait <= 0.0) break;
        ros::WallDuration(std::min(wait, 0.01)).sleep();
      }
      if (stop_ || !ros::ok()) break;
      publishClock(m.getTime());
      elapsed_ = rel;
      const std::string& topic = m.getTopic();
      if (topic == "/velodyne_points") {
        auto cloud = m.instantiate<sensor_msgs::PointCloud2>();
        // By the scan's stamp (its first revolution starts up to 0.2 s before it is recorded).
        const double stamp_rel = (cloud->header.stamp - start_).toSec();
        if (Faults::any(faults_.unknown_frame, stamp_rel)) cloud->header.frame_id = kUnknownFrame;
        scan_pub_.publish(cloud);
        std::lock_guard<std::mutex> lock(scan_mutex_);
        last_scan_ = cloud;
      } else if (topic == "/imu/data") {
        if (!Faults::any(faults_.no_imu, rel)) imu_pub_.publish(m.instantiate<sensor_msgs::Imu>());
      } else if (topic == "/ins/odom") {
        if (!Faults::any(faults_.no_ins, rel)) {
          odom_pub_.publish(m.instantiate<nav_msgs::Odometry>());
        }
      } else if (topic == "/tf") {
        if (!Faults::any(faults_.no_ins, rel))
          tf_pub_.publish(m.instantiate<tf2_msgs::TFMessage>());
      } else if (topic == "/tf_static") {
        tf_static_pub_.publish(m.instantiate<tf2_msgs::TFMessage>());
      }
    }
    finished_ = true;
  }

  Faults faults_;
  rosbag::Bag bag_;
  Truth truth_;
  ros::Time start_, end_;
  ros::Publisher clock_pub_, scan_pub_, odom_pub_, imu_pub_, tf_pub_, tf_static_pub_;
  std::thread thread_;
  std::atomic<bool> stop_{false}, held_{false}, finished_{false};
  std::atomic<double> elapsed_{0.0};
  mutable std::mutex scan_mutex_;
  sensor_msgs::PointCloud2ConstPtr last_scan_;
};

}  // namespace vehicle_test
}  // namespace node
}  // namespace gmm_localization
