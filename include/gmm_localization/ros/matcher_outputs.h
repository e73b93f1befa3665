#pragma once
// MatchReport (core) -> the matcher's output messages. Pure functions (no master needed); the
// caller sets header stamps where noted and decides what to publish.

#include <cstdint>
#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/matching/traversal_image.h"

namespace gmm_localization {
namespace node {

/// Status of one scan (stamp = the scan's, frame = map_frame). latency_s: scan stamp to
/// publication [s]; dropped: stale scans dropped since the previous status. The pose field
/// holds the result (accepted or not), else the prior, else identity; never a NaN.
void toStatusMsg(const MatchReport& report, const std::string& map_frame, double latency_s,
                 uint32_t dropped, MatchStatus& msg);

/// The accepted pose at the scan stamp in map_frame with its 6x6 covariance. Returns false,
/// leaving msg unspecified, when the report is not accepted or any number is not finite.
bool toMatchPoseMsg(const MatchReport& report, const std::string& map_frame,
                    geometry_msgs::PoseWithCovarianceStamped& msg);

/// The points labelled obstacle (paper V-C), x y z float32, in base_link or, with in_map, placed
/// at the registered pose. False when the report has no labels.
bool toObstaclesCloud(const MatchReport& report, bool in_map, sensor_msgs::PointCloud2& msg);

/// The whole scan placed at the registered pose (map frame), fields x y z mahalanobis (float32,
/// clamped to max_mahalanobis: +inf over empty cells) and class (uint8: 0 map, 1 obstacle), for
/// rviz colouring like the paper's Fig. 11. False when the report has no labels.
bool toClassifiedCloud(const MatchReport& report, double max_mahalanobis,
                       sensor_msgs::PointCloud2& msg);

/// The branch-and-bound traversal picture (paper Fig. 9) as an rgb8 image. False when the
/// report has no traversal.
bool toTraversalImage(const MatchReport& report, const TraversalImageOptions& options,
                      sensor_msgs::Image& msg);

}  // namespace node
}  // namespace gmm_localization
