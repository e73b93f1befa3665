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

/// How a cloud's per-point times were read (CloudData::time_kind).
enum class PointTimeKind {
  kNone,                 ///< no time field (or an empty cloud): time_s empty
  kRelativeSeconds,      ///< float seconds after header.stamp (velodyne_pointcloud `time`)
  kRelativeNanoseconds,  ///< nanoseconds after header.stamp (Ouster uint32 `t`)
  kAbsoluteSeconds,      ///< float64 seconds since the epoch (Hesai, RoboSense `timestamp`)
  kAbsoluteNanoseconds,  ///< float64 nanoseconds since the epoch (Livox `timestamp`)
  kRefused,              ///< times that make no sense: time_s empty, CloudData::time_problem why
};
/// "none", "relative seconds", "relative nanoseconds", "absolute seconds",
/// "absolute nanoseconds", "refused".
const char* pointTimeKindName(PointTimeKind kind);

/// Per-point time fields looked for, in this order: the first whose values make sense is used.
extern const char* const kPointTimeFields[3];  // "time", "t", "timestamp"
/// Every finite converted time must lie within this of header.stamp [s] ...
constexpr double kMaxPointTimeOffsetS = 1.0;
/// ... and all of them within this span [s] (one revolution, or a few merged ones) ...
constexpr double kMaxPointTimeSpanS = 1.0;
/// ... read to this resolution or better [s] (float32 cannot hold absolute times).
constexpr double kMaxPointTimeQuantumS = 1e-3;

/// The per-point times of one field, relative to the stamp.
struct PointTimes {
  PointTimeKind kind = PointTimeKind::kNone;
  std::vector<float> time_s;  ///< relative to the stamp [s] (empty when refused)
  std::string problem;        ///< why refused (names the field, its values and the stamp)
};

/// Decides what the raw values of the time field `field` (datatype a PointField constant,
/// each value read as double) mean, from their magnitude against the stamp, and converts them
/// to seconds after the stamp. usable[i] false (a point with a non-finite coordinate): that
/// point's time is ignored by the checks and converted as it is (empty usable: all usable).
/// Readings tried, in order: for float fields seconds after the stamp, absolute seconds,
/// absolute nanoseconds; for 4-byte integer fields nanoseconds after the stamp. 1- and 2-byte
/// integers are refused (unit unknown), and float nanoseconds after the stamp are not tried
/// (almost any garbage would pass as them). A reading fits when every usable time lies within
/// kMaxPointTimeOffsetS of the stamp and within kMaxPointTimeSpanS of each other, and the
/// datatype resolves it to kMaxPointTimeQuantumS; when relative and absolute seconds both fit
/// (a stamp near 0, sim time), the one nearer the stamp wins, relative on a tie. A usable point
/// with a non-finite time, or no reading that fits, refuses the times.
PointTimes interpretPointTimes(const std::string& field, uint8_t datatype,
                               const std::vector<double>& raw, const std::vector<bool>& usable,
                               const ros::Time& stamp);

/// The parts of a LIDAR cloud the stack uses. Optional fields are empty when absent.
struct CloudData {
  PointList points;           ///< x, y, z in the message's frame [m] (NaN kept)
  std::vector<float> time_s;  ///< per-point time relative to header.stamp [s]
  std::vector<float> intensity;
  std::vector<uint16_t> ring;
  std::vector<uint8_t> label;  ///< simulator ground truth (0 map, 1 dynamic, 2 snow)
  /// The time field read into time_s (when refused: the first one present), its datatype and
  /// how its values were read; time_problem: why refused (every field present), else empty.
  std::string time_field;
  uint8_t time_datatype = 0;
  PointTimeKind time_kind = PointTimeKind::kNone;
  std::string time_problem;
};

/// e.g. "'timestamp' float64 absolute seconds"; empty when no time field was used.
std::string describePointTimes(const CloudData& cloud);

/// What a driver should publish instead of times that were refused (for log messages).
const char* pointTimeFixHint();

/// Reads a cloud. Accepts float32 or float64 x, y, z; a per-point time (see below); uint16
/// "ring"; float32 "intensity"; uint8 "label". Fails with a reason naming the problem.
/// Per-point time: `time_field` when given, else the first of kPointTimeFields that makes sense
/// (interpretPointTimes): velodyne_pointcloud `time` (float32 s after the stamp, negative when
/// the stamp is the revolution's end), Ouster `t` (uint32 ns), Hesai and RoboSense `timestamp`
/// (float64 absolute s), Livox `timestamp` (float64 absolute ns): any name may hold any of
/// these, told apart by magnitude against header.stamp. Times that make no sense
/// leave time_s empty (the scan is then not deskewed) with time_problem saying why; they do not
/// reject the cloud. A time field whose layout is broken (datatype, count, offset) does.
/// "ring" and "label" may have any numeric datatype, but every value must be finite and within
/// [0, 65535] resp. [0, 255] (fractions are truncated): otherwise the whole cloud is rejected,
/// naming the field, the point and the value (a sensor driver emitting such values is broken,
/// and silently clamping would mislabel points). Float values beyond the float32 range (from
/// float64 fields) become +-inf. A cloud with width or height 0 that passes the size and field
/// checks is the empty cloud (0 points, every channel empty), whatever the other dimension; the
/// work is bounded by the data (never by width x height alone).
Result<CloudData> fromMsg(const sensor_msgs::PointCloud2& msg, const std::string& time_field = {});

/// Writes x, y, z (float32) and, when their sizes match, intensity, time, ring and label.
/// extra_float_name/extra_float add one more float32 field (e.g. "likelihood").
void toMsg(const CloudData& cloud, sensor_msgs::PointCloud2& msg,
           const std::string& extra_float_name = {}, const std::vector<float>& extra_float = {});

}  // namespace node
}  // namespace gmm_localization
