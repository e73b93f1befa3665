#pragma once
// Parameters of the cloud merger (config/cloud_merger.yaml documents each key), loaded once from
// the private node handle; a bad value throws ConfigError naming the key.

#include <string>
#include <vector>

#include <ros/node_handle.h>

#include "gmm_localization/ros/cloud_merger_sync.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct CloudMergerOptions {
  /// One topic per sensor (relative names), in the order the merged cloud concatenates them.
  std::vector<std::string> input_topics = {
      "velodyne_0/velodyne_points", "velodyne_1/velodyne_points", "velodyne_2/velodyne_points",
      "velodyne_3/velodyne_points"};
  std::string output_frame = "base_link";
  /// Synchronisation policy (cloud_merger_sync.h); sync.sensors = input_topics.size().
  MergeSyncOptions sync;
  double expected_rate_hz = 10.0;  ///< per sensor; diagnostics warn outside [0.5x, 1.5x]
  int input_queue_size = 2;        ///< subscriber queue per input topic [messages]
};

/// Reads and validates the options through a ParamSource (params.h; the nodelet passes its
/// private node handle). Throws ConfigError naming the key.
CloudMergerOptions loadCloudMergerOptions(const ParamSource& pnh);

}  // namespace node
}  // namespace gmm_localization
