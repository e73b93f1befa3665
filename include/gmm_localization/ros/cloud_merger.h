#pragma once
// The cloud merger: merges the sensors' clouds (four HDL-32Es) into one scan
// in output_frame (base_link) and publishes it as velodyne_points.
//
// Topics (relative; remap in launch):
//   <input_topics[i]>  sensor_msgs/PointCloud2 from sensor i, in its own frame (velodyne_i).
//   velodyne_points    sensor_msgs/PointCloud2 in output_frame, dense (no non-finite point),
//                      stamped with the earliest input stamp of its set; fields x y z, then
//                      intensity, time [s, relative to the stamp], ring, label where the
//                      inputs have them (cloud_merger_assembly.h). The points of a sensor
//                      whose per-point times the reader refuses (or which has none while
//                      another sensor has some) get NaN times, so the matcher refuses the
//                      scan's times ("not finite") and does not deskew it; a throttled warning
//                      names the sensor and the reader's reason, and the input's diagnostics
//                      count such clouds.
// Synchronisation: cloud_merger_sync.h (a set = one revolution per sensor; published when all
// have arrived, after max_wait_s, or when the next set begins; late clouds dropped; time going
// backwards resets).
// Extrinsics: TF output_frame <- cloud frame at the latest time (static extrinsics), looked up
// for every cloud; the last transform found for a frame is reused if a lookup fails (tf2 clears
// its buffer, /tf_static included, when time jumps back). A sensor with no transform yet is
// skipped with a throttled warning and a diagnostic.
// Malformed clouds (node::fromMsg of a cloud: missing x/y/z, sizes that disagree, unsupported
// types, big-endian) are dropped with a throttled warning and a diagnostic naming the reason.
// Diagnostics: per input (rate, clouds, malformed, no TF, late, out of window, non-finite points
// dropped, clouds merged without valid per-point times and why), output (rate, complete /
// incomplete sets, missing sensors, scans with NaN point times, merge latency, resets).

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <Eigen/Geometry>

#include "gmm_localization/ros/cloud_merger_options.h"
#include "gmm_localization/ros/cloud_merger_sync.h"
#include "gmm_localization/ros/diagnostics.h"

namespace gmm_localization {
namespace node {

class CloudMerger {
 public:
  /// Throws ConfigError on a bad parameter.
  CloudMerger(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~CloudMerger();
  CloudMerger(const CloudMerger&) = delete;
  CloudMerger& operator=(const CloudMerger&) = delete;

 private:
  /// Per-sensor state and counters (guarded by mutex_).
  struct Input {
    Input(std::string t, double expected_hz)
        : topic(std::move(t)), rate(0.5 * expected_hz, 1.5 * expected_hz) {}
    std::string topic;
    std::string frame;  ///< frame_id of the last cloud
    FrequencyMonitor rate;
    uint64_t received = 0, malformed = 0, no_tf = 0, late = 0, out_of_window = 0;
    uint64_t nonfinite_points = 0;
    uint64_t untimed = 0;                        ///< clouds merged with NaN times (refused or none)
    std::string last_time_problem;               ///< why, for the last of them
    double last_time_problem_s = -1e9;           ///< wall time of last_time_problem [s]
    std::string last_error;                      ///< the last malformed-cloud or TF problem
    double last_error_time_s = -1e9;             ///< wall time of last_error [s]
    double last_log_s = -1e9;                    ///< wall time of the last warning logged [s]
    std::optional<Eigen::Isometry3d> extrinsic;  ///< output_T_sensor last found in TF
    std::string extrinsic_frame;
  };

  // cloud_merger.cpp
  void onCloud(const sensor_msgs::PointCloud2::ConstPtr& msg, size_t sensor);
  void onPoll();
  void publish(const MergeCycle& cycle);
  bool extrinsic(Input& input, const std::string& frame, Eigen::Isometry3d& T);
  /// ROS_WARN throttled per input (one sensor's trouble must not hide another's).
  void warn(Input& input, const std::string& what);
  // cloud_merger_diagnostics.cpp
  void setUpDiagnostics();

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  CloudMergerOptions options_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::vector<std::unique_ptr<Input>> inputs_;
  std::vector<ros::Subscriber> subs_;
  ros::Publisher pub_;
  ros::WallTimer poll_timer_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex mutex_;  // guards the synchroniser and every counter
  MergeSynchronizer sync_;
  FrequencyMonitor output_rate_;
  uint64_t published_ = 0;
  uint64_t untimed_scans_ = 0;  // scans published with NaN point times for some sensor
  std::vector<size_t> last_missing_;
  double last_missing_time_s_ = -1e9;  // wall time of the last incomplete set [s]
  double last_latency_ms_ = 0.0, sum_latency_ms_ = 0.0, max_latency_ms_ = 0.0;
  size_t last_points_ = 0;
};

}  // namespace node
}  // namespace gmm_localization
