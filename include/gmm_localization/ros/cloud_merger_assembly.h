#pragma once
// The cloud merger's geometry (pure): moving a sensor's cloud into the output frame and
// concatenating a cycle's clouds into one scan with re-based per-point times. A merged scan
// claims per-point times only for points whose sensor gave valid ones (NaN otherwise).
//
// Non-finite points (no-return slots of organised clouds, driver glitches) are dropped here and
// counted: every consumer filters them anyway, and a merged cloud of four HDL-32Es is large
// enough that carrying dead points costs real bandwidth. The merged cloud is therefore dense.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/cloud_merger_sync.h"

namespace gmm_localization {
namespace node {

/// out = in with every point moved by output_T_sensor (computed in double precision), minus
/// the points with a non-finite coordinate. Optional fields follow their points; a field whose
/// size differs from the point count is left out. How the times were read (time_field,
/// time_datatype, time_kind, time_problem) is kept. Returns the number of points dropped.
size_t transformCloud(const CloudData& in, const Eigen::Isometry3d& output_T_sensor,
                      CloudData& out);

/// An input of a merged cycle whose points got NaN times in the merged cloud.
struct UntimedInput {
  size_t sensor = 0;     ///< MergeInput::sensor
  bool refused = false;  ///< its times were refused by the reader (else it has none)
  std::string reason;    ///< the reader's refusal (CloudData::time_problem), or why none
};

/// Concatenates the cycle's clouds in sensor order. time_s of each point becomes its time
/// relative to the cycle's stamp: time + (input stamp - cycle stamp). The time field is present
/// when any input has one, valid or refused by the reader (CloudData::time_kind kRefused); the
/// points of an input whose times were refused, or which has none, then get NaN times, so that
/// the merged cloud's reader refuses its times ("not finite") instead of deskewing with times
/// that are not the points' (such inputs are listed in `untimed` when given). Without any time
/// field the merged cloud has none. Intensity, ring and label only when every input has them
/// (no invented values).
CloudData mergeCycle(const MergeCycle& cycle, std::vector<UntimedInput>* untimed = nullptr);

}  // namespace node
}  // namespace gmm_localization
