#include "gmm_localization/ros/cloud_merger_assembly.h"

#include <cmath>
#include <limits>

namespace gmm_localization {
namespace node {
namespace {

/// Valid per-point times: read by the reader (not refused), one per point.
bool hasTimes(const CloudData& c) {
  return c.time_kind != PointTimeKind::kRefused && c.time_s.size() == c.points.size();
}

UntimedInput untimedInput(size_t sensor, const CloudData& c) {
  UntimedInput u;
  u.sensor = sensor;
  u.refused = c.time_kind == PointTimeKind::kRefused;
  if (u.refused) {
    u.reason = "per-point times refused: " +
               (c.time_problem.empty() ? std::string("(no reason given)") : c.time_problem);
  } else if (!c.time_s.empty()) {
    u.reason = "per-point times and points differ in number (" + std::to_string(c.time_s.size()) +
               " times, " + std::to_string(c.points.size()) + " points)";
  } else {
    u.reason =
        "no per-point time field ('time', 't' or 'timestamp') while another sensor's "
        "cloud of the set has one";
  }
  return u;
}

}  // namespace

size_t transformCloud(const CloudData& in, const Eigen::Isometry3d& output_T_sensor,
                      CloudData& out) {
  const size_t n = in.points.size();
  const bool has_t = in.time_s.size() == n, has_i = in.intensity.size() == n;
  const bool has_r = in.ring.size() == n, has_l = in.label.size() == n;
  out = CloudData();
  out.time_field = in.time_field;
  out.time_datatype = in.time_datatype;
  out.time_kind = in.time_kind;
  out.time_problem = in.time_problem;
  out.points.reserve(n);
  if (has_t) out.time_s.reserve(n);
  if (has_i) out.intensity.reserve(n);
  if (has_r) out.ring.reserve(n);
  if (has_l) out.label.reserve(n);
  const Eigen::Matrix3d R = output_T_sensor.linear();
  const Eigen::Vector3d t = output_T_sensor.translation();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = in.points[i];
    if (!p.allFinite()) continue;
    out.points.push_back((R * p.cast<double>() + t).cast<float>());
    if (has_t) out.time_s.push_back(in.time_s[i]);
    if (has_i) out.intensity.push_back(in.intensity[i]);
    if (has_r) out.ring.push_back(in.ring[i]);
    if (has_l) out.label.push_back(in.label[i]);
  }
  return n - out.points.size();
}

CloudData mergeCycle(const MergeCycle& cycle, std::vector<UntimedInput>* untimed) {
  CloudData out;
  size_t total = 0;
  bool any_t = false, all_i = true, all_r = true, all_l = true;
  for (const MergeInput& in : cycle.inputs) {
    if (!in.cloud) continue;
    const CloudData& c = *in.cloud;
    const size_t n = c.points.size();
    total += n;
    // A refused time field counts: its points must not pass for untimed-but-valid ones.
    any_t = any_t || (n > 0 && (hasTimes(c) || c.time_kind == PointTimeKind::kRefused));
    all_i = all_i && c.intensity.size() == n;
    all_r = all_r && c.ring.size() == n;
    all_l = all_l && c.label.size() == n;
  }
  out.points.reserve(total);
  if (any_t) out.time_s.reserve(total);
  if (all_i) out.intensity.reserve(total);
  if (all_r) out.ring.reserve(total);
  if (all_l) out.label.reserve(total);
  for (const MergeInput& in : cycle.inputs) {
    if (!in.cloud) continue;
    const CloudData& c = *in.cloud;
    const size_t n = c.points.size();
    out.points.insert(out.points.end(), c.points.begin(), c.points.end());
    if (any_t && hasTimes(c)) {
      // Offsets are small (a period or two), so float keeps microseconds.
      const double offset_s = static_cast<double>(in.stamp_ns - cycle.stamp_ns) * 1e-9;
      for (size_t i = 0; i < n; ++i) {
        out.time_s.push_back(static_cast<float>(c.time_s[i] + offset_s));
      }
    } else if (any_t && n > 0) {
      // The cloud's offset alone would pass for valid times (every point at its stamp).
      out.time_s.insert(out.time_s.end(), n, std::numeric_limits<float>::quiet_NaN());
      if (untimed != nullptr) untimed->push_back(untimedInput(in.sensor, c));
    }
    if (all_i) out.intensity.insert(out.intensity.end(), c.intensity.begin(), c.intensity.end());
    if (all_r) out.ring.insert(out.ring.end(), c.ring.begin(), c.ring.end());
    if (all_l) out.label.insert(out.label.end(), c.label.begin(), c.label.end());
  }
  if (total == 0) out = CloudData();  // no field without points
  return out;
}

}  // namespace node
}  // namespace gmm_localization
