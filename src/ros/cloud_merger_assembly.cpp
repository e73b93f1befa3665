#include "gmm_localization/ros/cloud_merger_assembly.h"

#include <cmath>

namespace gmm_localization {
namespace node {

size_t transformCloud(const CloudData& in, const Eigen::Isometry3d& output_T_sensor,
                      CloudData& out) {
  const size_t n = in.points.size();
  const bool has_t = in.time_s.size() == n, has_i = in.intensity.size() == n;
  const bool has_r = in.ring.size() == n, has_l = in.label.size() == n;
  out = CloudData();
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

CloudData mergeCycle(const MergeCycle& cycle) {
  CloudData out;
  size_t total = 0;
  bool any_t = false, all_i = true, all_r = true, all_l = true;
  for (const MergeInput& in : cycle.inputs) {
    if (!in.cloud) continue;
    const CloudData& c = *in.cloud;
    const size_t n = c.points.size();
    total += n;
    any_t = any_t || (n > 0 && c.time_s.size() == n);
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
    if (any_t) {
      // Offsets are small (a period or two), so float keeps microseconds.
      const double offset_s = static_cast<double>(in.stamp_ns - cycle.stamp_ns) * 1e-9;
      const bool own = c.time_s.size() == n;
      for (size_t i = 0; i < n; ++i) {
        out.time_s.push_back(static_cast<float>((own ? c.time_s[i] : 0.0) + offset_s));
      }
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
