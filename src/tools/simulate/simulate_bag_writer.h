#pragma once
// BagSink: writes a simulation to a rosbag with standard message types.
//   /velodyne_N/velodyne_points  sensor_msgs/PointCloud2  frame velodyne_N (optional)
//   /velodyne_points             sensor_msgs/PointCloud2  frame base_link (merged)
//   /ins/odom                    nav_msgs/Odometry        frame odom, child base_link
//   /imu/data                    sensor_msgs/Imu          frame base_link
//   /ground_truth/odom           nav_msgs/Odometry        frame map, child base_link
//   /tf                          tf2_msgs/TFMessage       odom -> base_link (from the INS)
//   /tf_static                   tf2_msgs/TFMessage       base_link -> velodyne_N (latched)
//   /gnss/fix                    sensor_msgs/NavSatFix    frame base_link (simulate --gnss)
// Cloud fields: x y z intensity (float32), ring (uint16), label (uint8), time (float32, seconds
// since header.stamp = revolution start, or the earliest start for the merged cloud).
// Stamps are epoch + trajectory time; each message is recorded at the time it becomes
// available (scans at the end of their revolution), so `rosbag play --clock` works.

#include <memory>
#include <string>

#include <rosbag/bag.h>
#include <sensor_msgs/NavSatFix.h>

#include "gmm_localization/sim/simulation.h"

namespace gmm_localization {
namespace tools {

struct BagOptions {
  std::string path;
  bool lz4 = false;
  bool per_sensor_clouds = false;
  bool merged_cloud = true;
  double epoch_s = 1600000000.0;
};

class BagSink : public sim::SimulationSink {
 public:
  /// Opens the bag and writes /tf_static. Throws nothing; errors come back as Status.
  static Result<std::unique_ptr<BagSink>> open(const BagOptions& options,
                                               const sim::SimulationConfig& config, double t_begin);
  ~BagSink() override;
  Status onRevolution(const sim::SensorRevolution& rev) override;
  Status onMergedScan(const sim::MergedScan& scan) override;
  Status onGroundTruth(const sim::VehicleState& s) override;
  Status onOdometry(const sim::OdomSample& o) override;
  Status onImu(const sim::ImuSample& m) override;
  /// A GNSS fix (simulate_gnss.h), written on `topic` at its stamp.
  Status onGnssFix(const std::string& topic, const sensor_msgs::NavSatFix& fix);
  Status close();

 private:
  BagSink() = default;
  ros::Time stamp(double t) const { return ros::Time(options_.epoch_s + t); }
  BagOptions options_;
  sim::SimulationConfig config_;
  rosbag::Bag bag_;
  bool open_ = false;
};

}  // namespace tools
}  // namespace gmm_localization
