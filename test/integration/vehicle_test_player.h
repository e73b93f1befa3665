#pragma once
// A rosbag player for the robustness and kidnap rostests (vehicle_robustness_test.cpp,
// vehicle_kidnap_test.cpp): plays the fixture's drive on sim time (/clock = bag time, rate 1)
// like `rosbag play -(-)clock`, and injects faults by bag time: IMU dropouts, INS dropouts
// (odometry and TF odom -> base_link), scans in a frame TF does not know, a kidnap (the bag
// spliced: the vehicle jumps to another place of the drive while the INS carries on as if it had
// not moved). It can hold the clock (a stopped recording) and resume.
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
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
  /// A kidnap (NaN: none): the bag is played up to kidnap_at_s, then from kidnap_to_s on, that
  /// part's stamps shifted by kidnap_at_s - kidnap_to_s so that time runs on. The truth jumps
  /// there; the INS odometry poses, TF odom -> base_link and the IMU orientation continue from
  /// where they were (moved by the same rigid correction), as an INS that did not notice.
  double kidnap_at_s = NAN, kidnap_to_s = NAN;
  bool kidnap() const { return std::isfinite(kidnap_at_s) && std::isfinite(kidnap_to_s); }
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
    rosbag::View all(bag_);
    start_ = all.getBeginTime();
    end_ = bag_end_ = all.getEndTime();
    segments_.push_back({0.0, (end_ - start_).toSec() + 1.0, 0.0});
    if (faults_.kidnap()) {
      segments_ = {
          {0.0, faults_.kidnap_at_s, 0.0},
          {faults_.kidnap_to_s, segments_[0].to_s, faults_.kidnap_at_s - faults_.kidnap_to_s}};
      end_ += ros::Duration(segments_[1].shift_s);
      // The second part is moved by odom(at) * odom(to)^-1 (the INS's odom -> base_link at both
      // ends of the splice) so that it starts where the first ended.
      segments_[1].ins_correction =
          insPoseNear(faults_.kidnap_at_s) * insPoseNear(faults_.kidnap_to_s).inverse();
    }
    // The truth as played, segment after segment (a stretch played twice is in it twice).
    std::vector<std::pair<double, Pose6>> bag_truth;
    rosbag::View gt(bag_, rosbag::TopicQuery(std::vector<std::string>{"/ground_truth/odom"}));
    for (const rosbag::MessageInstance& m : gt) {
      const auto odom = m.instantiate<nav_msgs::Odometry>();
      if (odom) bag_truth.emplace_back(odom->header.stamp.toSec(), toPose(odom->pose.pose));
    }
    for (const Segment& s : segments_) {
      for (const auto& [stamp, pose] : bag_truth) {
        const double rel = stamp - start_.toSec();
        if (rel >= s.from_s && rel < s.to_s) truth_.add(stamp + s.shift_s, pose);
      }
    }
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

  /// The truth as played (after a kidnap: where the vehicle then is, on the shifted stamps).
  const Truth& truth() const { return truth_; }
  ros::Time start() const { return start_; }
  /// The last message's time as played (a kidnap shortens or lengthens the drive).
  ros::Time end() const { return end_; }
  /// Time of the last published message as played [s since the start].
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

  /// A stretch of the bag [from_s, to_s) (relative to its start) played shifted by shift_s,
  /// its INS moved by ins_correction.
  struct Segment {
    double from_s = 0.0, to_s = 0.0, shift_s = 0.0;
    Eigen::Isometry3d ins_correction = Eigen::Isometry3d::Identity();
  };

  /// The INS's odom -> base_link of the /ins/odom message nearest to bag time rel_s.
  Eigen::Isometry3d insPoseNear(double rel_s) {
    rosbag::View ins(bag_, rosbag::TopicQuery(std::vector<std::string>{"/ins/odom"}));
    Eigen::Isometry3d best = Eigen::Isometry3d::Identity();
    double best_gap = std::numeric_limits<double>::infinity();
    for (const rosbag::MessageInstance& m : ins) {
      const auto odom = m.instantiate<nav_msgs::Odometry>();
      if (!odom) continue;
      const double gap = std::abs((odom->header.stamp - start_).toSec() - rel_s);
      if (gap < best_gap) {
        best_gap = gap;
        tf2::fromMsg(odom->pose.pose, best);
      }
    }
    return best;
  }

  void run() {
    ros::WallTime wall_start = ros::WallTime::now();
    for (const Segment& segment : segments_) {
      rosbag::View view(bag_,
                        rosbag::TopicQuery(std::vector<std::string>{
                            "/velodyne_points", "/ins/odom", "/imu/data", "/tf", "/tf_static"}),
                        start_ + ros::Duration(segment.from_s),
                        std::min(bag_end_, start_ + ros::Duration(std::max(segment.from_s,
                                                                           segment.to_s - 1e-9))));
      if (!playSegment(view, segment, wall_start)) break;
    }
    finished_ = true;
  }

  /// Plays one segment; false when stopped.
  bool playSegment(rosbag::View& view, const Segment& segment, ros::WallTime& wall_start) {
    const ros::Duration shift(segment.shift_s);
    const Eigen::Isometry3d& fix = segment.ins_correction;
    const bool moved = !fix.isApprox(Eigen::Isometry3d::Identity());
    for (const rosbag::MessageInstance& m : view) {
      const double rel = (m.getTime() - start_).toSec() + segment.shift_s;
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
      if (stop_ || !ros::ok()) return false;
      publishClock(m.getTime() + shift);
      elapsed_ = rel;
      const std::string& topic = m.getTopic();
      if (topic == "/velodyne_points") {
        auto cloud = m.instantiate<sensor_msgs::PointCloud2>();
        cloud->header.stamp += shift;
        // By the scan's stamp (its first revolution starts up to 0.2 s before it is recorded).
        const double stamp_rel = (cloud->header.stamp - start_).toSec();
        if (Faults::any(faults_.unknown_frame, stamp_rel)) cloud->header.frame_id = kUnknownFrame;
        scan_pub_.publish(cloud);
        std::lock_guard<std::mutex> lock(scan_mutex_);
        last_scan_ = cloud;
      } else if (topic == "/imu/data") {
        if (Faults::any(faults_.no_imu, rel)) continue;
        auto imu = m.instantiate<sensor_msgs::Imu>();
        imu->header.stamp += shift;
        if (moved) {
          Eigen::Quaterniond q;
          tf2::fromMsg(imu->orientation, q);
          imu->orientation = tf2::toMsg(Eigen::Quaterniond(fix.rotation()) * q);
        }
        imu_pub_.publish(imu);
      } else if (topic == "/ins/odom") {
        if (Faults::any(faults_.no_ins, rel)) continue;
        auto odom = m.instantiate<nav_msgs::Odometry>();
        odom->header.stamp += shift;
        if (moved) {
          Eigen::Isometry3d pose;
          tf2::fromMsg(odom->pose.pose, pose);
          odom->pose.pose = tf2::toMsg(Eigen::Isometry3d(fix * pose));
        }
        odom_pub_.publish(odom);
      } else if (topic == "/tf") {
        if (Faults::any(faults_.no_ins, rel)) continue;
        auto tf = m.instantiate<tf2_msgs::TFMessage>();
        for (geometry_msgs::TransformStamped& t : tf->transforms) {
          t.header.stamp += shift;
          if (moved) t.transform = tf2::eigenToTransform(fix * tf2::transformToEigen(t)).transform;
        }
        tf_pub_.publish(tf);
      } else if (topic == "/tf_static") {
        tf_static_pub_.publish(m.instantiate<tf2_msgs::TFMessage>());
      }
    }
    return true;
  }

  Faults faults_;
  rosbag::Bag bag_;
  Truth truth_;
  ros::Time start_, end_, bag_end_;
  std::vector<Segment> segments_;
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
