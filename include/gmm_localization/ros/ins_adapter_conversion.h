#pragma once
// The INS adapter's work on one message, without a node: a driver's nav_msgs/Odometry in, the
// odometry of base_link in odom out (pose odom -> base_link, twist in base_link) with its
// transform. The nodelet (ins_adapter.h) wraps it; the tests feed it bags directly.
//
// The lever arm base_frame <- child frame comes from TF (a static extrinsic: looked up until
// found, then kept for that frame). The maths is core/filter/ins_frames.h.

#include <map>
#include <string>

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <tf2/buffer_core.h>
#include <Eigen/Geometry>

#include "gmm_localization/core/filter/ins_frames.h"
#include "gmm_localization/ros/ins_adapter_options.h"

namespace gmm_localization {
namespace node {

/// A driver message as numbers (no convention applied).
InsReport insReportFromMsg(const nav_msgs::Odometry& msg);

enum class InsAdapterOutcome {
  kPublished,    ///< odometry (and transform) to publish
  kNoTransform,  ///< no TF base_frame <- child frame yet: dropped
  kInvalid,      ///< non-finite values, a bad quaternion: dropped
  kOutOfOrder,   ///< stamp not after the newest: dropped
};
const char* insAdapterOutcomeName(InsAdapterOutcome o);

struct InsAdapterResult {
  InsAdapterOutcome outcome = InsAdapterOutcome::kInvalid;
  std::string reason;  ///< why it was dropped (empty when published)
  InsOdometryStep step = InsOdometryStep::kStarted;
  double dt_s = 0.0;            ///< interval since the previous message (see InsOdometry::Update)
  std::string child_frame;      ///< the frame the message was read for
  nav_msgs::Odometry odometry;  ///< odom_frame, child base_frame
  geometry_msgs::TransformStamped transform;  ///< odom_frame -> base_frame, same stamp
};

class InsOdometryAdapter {
 public:
  explicit InsOdometryAdapter(const InsAdapterOptions& options);

  /// Converts one driver message; `tf` holds base_frame <- the child frame.
  InsAdapterResult process(const nav_msgs::Odometry& msg, const tf2::BufferCore& tf);

  const InsAdapterOptions& options() const { return options_; }
  /// The lever arm found for a child frame (base_T_child), if any.
  const Eigen::Isometry3d* extrinsic(const std::string& child_frame) const;

 private:
  InsAdapterOptions options_;
  InsOdometry odometry_;
  std::map<std::string, Eigen::Isometry3d> extrinsics_;  ///< base_T_child per child frame
};

}  // namespace node
}  // namespace gmm_localization
