#pragma once
// sensor_msgs/PointCloud2 <-> core point lists, with validation: a malformed cloud (missing x/y/z,
// wrong field types, sizes that disagree) gives a reason, never a crash or garbage.

#include <string>
#include <vector>

#include <sensor_msgs/PointCloud2.h>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/matching/scan_filter.h"

namespace gmm_localization {
namespace node {

/// The parts of a LIDAR cloud the stack uses. Optional fields are empty when absent.
struct CloudData {
  PointList points;           ///< x, y, z in the message's frame [m] (NaN kept)
  std::vector<float> time_s;  ///< per-point time relative to header.stamp [s]
  std::vector<float> intensity;
  std::vector<uint16_t> ring;
  std::vector<uint8_t> label;  ///< simulator ground truth (0 map, 1 dynamic, 2 snow)
};

/// Reads a cloud. Accepts float32 or float64 x, y, z; a per-point time as float32/float64
/// seconds ("time", "t" when float) or uint32 nanoseconds ("t", Ouster style); uint16 "ring";
/// float32 "intensity"; uint8 "label". Fails with a reason naming the problem.
/// "ring" and "label" may have any numeric datatype, but every value must be finite and within
/// [0, 65535] resp. [0, 255] (fractions are truncated): otherwise the whole cloud is rejected,
/// naming the field, the point and the value (a sensor driver emitting such values is broken,
/// and silently clamping would mislabel points). Float values beyond the float32 range (from
/// float64 fields) become +-inf. A cloud with width or height 0 that passes the size and field
/// checks is the empty cloud (0 points, every channel empty), whatever the other dimension; the
/// work is bounded by the data (never by width x height alone).
Result<CloudData> fromMsg(const sensor_msgs::PointCloud2& msg);

/// Writes x, y, z (float32) and, when their sizes match, intensity, time, ring and label.
/// extra_float_name/extra_float add one more float32 field (e.g. "likelihood").
void toMsg(const CloudData& cloud, sensor_msgs::PointCloud2& msg,
           const std::string& extra_float_name = {}, const std::vector<float>& extra_float = {});

}  // namespace node
}  // namespace gmm_localization
