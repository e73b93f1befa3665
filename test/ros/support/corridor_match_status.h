#pragma once
// The MatchStatus of a cloud matched the way the matcher nodelet does it - read by the matcher's
// cloud reader, processed by MatchProcessor on the corridor map (test/unit/support/corridor_map.h)
// from a configured prior at the origin, converted by toStatusMsg - for the ROS-side tests of
// what a status says about a cloud (deskewed, point_times, deskew_note).
#include <utility>

#include <gtest/gtest.h>
#include <sensor_msgs/PointCloud2.h>

#include "../../unit/support/corridor_map.h"
#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/matcher_outputs.h"

namespace gmm_localization {
namespace testing {

/// `twist`: the deskew twist (null: none).
inline MatchStatus corridorMatchStatus(const sensor_msgs::PointCloud2& cloud,
                                       const BodyTwist* twist) {
  auto data = node::fromMsg(cloud);
  EXPECT_TRUE(data.ok()) << data.error();
  ScanInput scan;
  scan.stamp_s = cloud.header.stamp.toSec();
  if (data.ok()) {
    scan.points = data->points;
    scan.time_s = data->time_s;
    scan.time_source = node::describePointTimes(*data);
    scan.time_problem = data->time_problem;
  }
  auto processor = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions());
  EXPECT_TRUE(processor.ok()) << processor.error();
  static const ChunkMap map = corridorChunks();
  Prior prior;
  prior.source = PriorSource::kConfigured;
  const MatchReport report = processor->process(map, std::move(scan), prior, twist, false);
  MatchStatus s;
  node::toStatusMsg(report, "map", 0.0, 0, s);
  return s;
}

}  // namespace testing
}  // namespace gmm_localization
