#pragma once
// Reading a localization bag (docs/simulator.md: merged clouds, INS odometry, IMU, ground truth)
// for `evaluate`: messages are converted with the same functions the nodelets use
// (ros/cloud_conversion.h, ros/ekf_node_conversions.h) and handed over in bag (record) order.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <sensor_msgs/PointCloud2.h>

#include "evaluate/evaluate_metrics.h"
#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/localization/gnss_initial_pose.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {
namespace eval {

struct BagTopics {
  std::string cloud = "/velodyne_points";  ///< merged scans in base_frame (PointCloud2)
  std::string odom = "/ins/odom";          ///< INS odometry (nav_msgs/Odometry, odom frame)
  std::string imu = "/imu/data";           ///< sensor_msgs/Imu in base_frame
  std::string ground_truth = "/ground_truth/odom";  ///< nav_msgs/Odometry, map frame
  std::string base_frame = "base_link";
};

/// One merged scan with the simulator's per-point labels (empty when the cloud has none).
struct LabelledScan {
  ScanInput scan;
  std::vector<uint8_t> label;  ///< 0 static, 1 dynamic or changed, 2 snow
  double record_time_s = 0.0;  ///< when the bag recorded it (arrival) [s]
};

struct BagVisitor {
  std::function<void(const ImuMeasurement&)> imu;
  std::function<void(const OdometrySample&, const TwistMeasurement&)> odometry;
  std::function<void(LabelledScan&&)> scan;
  std::function<void(const PoseStamped2&)> ground_truth;
  /// GNSS fixes (sensor_msgs/NavSatFix on gnss_topic; evaluate --gps), converted as the ekf
  /// nodelet converts them (ros/gnss_conversion.h). Set: the bag must have the topic.
  std::function<void(const GnssFix&)> gnss;
  std::string gnss_topic = "/gnss/fix";
  /// Checked before each message: true stops the visit early (e.g. a duration limit).
  std::function<bool()> done;
};

/// Counts of what was read and what was skipped (with the reason in `problems`).
struct BagReadStats {
  uint64_t scans = 0, imu = 0, odometry = 0, ground_truth = 0, gnss = 0;
  uint64_t skipped = 0;
  std::vector<std::string> problems;  ///< first few reasons for skipped messages
  double first_stamp_s = 0.0, last_stamp_s = 0.0;
};

/// One merged cloud as the matcher reads it (Matcher::scanToBase: node::fromMsg, with how its
/// per-point times were read in time_source, or why they were refused in time_problem), with
/// its labels; record_time_s is left 0. Fails, with the reason, when the cloud is not in
/// base_frame (merged clouds only) or is malformed.
Result<LabelledScan> scanFromCloud(const sensor_msgs::PointCloud2& msg,
                                   const std::string& base_frame);

/// Visits every message of the four topics (five with visitor.gnss) in record order (callbacks may
/// be empty to skip a topic cheaply). Fails when the bag cannot be opened or lacks the cloud or
/// ground-truth topic.
Result<BagReadStats> visitLocalizationBag(const std::string& path, const BagTopics& topics,
                                          const BagVisitor& visitor);

/// The ground-truth trajectory alone (map -> base_frame), from a nav_msgs/Odometry topic.
Result<Trajectory> readTrajectory(const std::string& path, const std::string& topic);

/// The longest gap [s] of the ground truth (100 Hz) that Trajectory::at bridges for the scores.
constexpr double kTruthGapS = 0.1;

/// Number of messages on a topic (0 when the bag cannot be read).
size_t countMessages(const std::string& path, const std::string& topic);

/// Median of (record time - header stamp) over the first `max_scans` scans of the cloud topic
/// [s]: how late a scan reaches a subscriber during `rosbag play`. 0 without scans.
double medianScanRecordDelay(const std::string& path, const std::string& topic,
                             size_t max_scans = 50);

}  // namespace eval
}  // namespace gmm_localization
