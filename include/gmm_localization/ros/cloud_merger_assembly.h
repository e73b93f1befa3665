#pragma once
// The cloud merger's geometry (pure): moving a sensor's cloud into the output frame and
// concatenating a cycle's clouds into one scan with re-based per-point times.
//
// Non-finite points (no-return slots of organised clouds, driver glitches) are dropped here and
// counted: every consumer filters them anyway, and a merged cloud of four HDL-32Es is large
// enough that carrying dead points costs real bandwidth. The merged cloud is therefore dense.

#include <Eigen/Geometry>

#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/cloud_merger_sync.h"

namespace gmm_localization {
namespace node {

/// out = in with every point moved by output_T_sensor (computed in double precision), minus
/// the points with a non-finite coordinate. Optional fields follow their points; a field whose
/// size differs from the point count is left out. Returns the number of points dropped.
size_t transformCloud(const CloudData& in, const Eigen::Isometry3d& output_T_sensor,
                      CloudData& out);

/// Concatenates the cycle's clouds in sensor order. time_s of each point becomes its time
/// relative to the cycle's stamp: time + (input stamp - cycle stamp); points of a cloud without
/// per-point time get their cloud's offset. The time field is present when any input has one;
/// intensity, ring and label only when every input has them (no invented values).
CloudData mergeCycle(const MergeCycle& cycle);

}  // namespace node
}  // namespace gmm_localization
