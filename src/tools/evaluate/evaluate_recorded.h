#pragma once
// Mode B of `evaluate`: scores a bag recorded during a real `rosbag play` replay of the vehicle
// launch (launch/replay.launch record:=out.bag; topics in docs/ros.md): the EKF's odometry and
// the matcher's statuses (accepted pose, timing, latency) against the recorded ground truth.

#include <iosfwd>
#include <string>

#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace eval {

struct RecordedTopics {
  std::string ground_truth = "/ground_truth/odom";  ///< nav_msgs/Odometry, map frame
  std::string ekf = "/localization/odometry";       ///< nav_msgs/Odometry (EKF output)
  std::string status = "/localization/status";      ///< gmm_localization/MatchStatus
};

struct RecordedEvaluationConfig {
  std::string bag;         ///< the recording
  std::string source_bag;  ///< optional: the bag that was played (to count its scans)
  std::string cloud_topic = "/velodyne_points";  ///< scans of source_bag
  std::string dataset = "downtown";
  RecordedTopics topics;
  double ekf_rate_hz = 20.0;  ///< EKF messages are subsampled to this rate [Hz] (0: all)
};

Result<EvaluationResults> runRecordedEvaluation(const RecordedEvaluationConfig& config,
                                                std::ostream& log);

}  // namespace eval
}  // namespace gmm_localization
