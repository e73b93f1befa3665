#include "gmm_localization/core/scan_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Geometry>

namespace gmm_localization {

std::string ScanFilterOptions::validate() const {
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m)) {
    return "min_range_m=" + std::to_string(min_range_m) +
           ", max_range_m=" + std::to_string(max_range_m) + ": need 0 <= min_range_m < max_range_m";
  }
  if (!(max_height_m > min_height_m)) {
    return "min_height_m=" + std::to_string(min_height_m) +
           " must be below max_height_m=" + std::to_string(max_height_m);
  }
  if (!(voxel_m >= 0.0 && voxel_m <= 5.0)) {
    return "voxel_m=" + std::to_string(voxel_m) + " must be in [0, 5]";
  }
  return {};
}

FilteredScan filterScan(const PointList& base_points, double roll_rad, double pitch_rad,
                        const ScanFilterOptions& options) {
  FilteredScan out;
  out.input_points = base_points.size();
  const Eigen::Matrix3f level = (Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix()
                                    .cast<float>();
  const float r_min2 = static_cast<float>(options.min_range_m * options.min_range_m);
  const float r_max2 = static_cast<float>(options.max_range_m * options.max_range_m);
  PointList kept;
  kept.reserve(base_points.size());
  for (const Eigen::Vector3f& p : base_points) {
    if (!p.allFinite()) {
      ++out.dropped_nonfinite;
      continue;
    }
    const Eigen::Vector3f q = level * p;
    const float r2 = q.x() * q.x() + q.y() * q.y();
    if (r2 < r_min2 || r2 > r_max2) {
      ++out.dropped_range;
      continue;
    }
    if (q.z() < options.min_height_m || q.z() > options.max_height_m) {
      ++out.dropped_height;
      continue;
    }
    kept.push_back(q);
  }
  out.points = options.voxel_m > 0.0 ? voxelDownsample(kept, options.voxel_m) : std::move(kept);
  if (options.max_points > 0 && out.points.size() > options.max_points) {
    PointList thinned;
    thinned.reserve(options.max_points);
    const double stride = static_cast<double>(out.points.size()) / options.max_points;
    for (size_t i = 0; i < options.max_points; ++i) {
      thinned.push_back(out.points[static_cast<size_t>(i * stride)]);
    }
    out.points = std::move(thinned);
  }
  return out;
}

PointList voxelDownsample(const PointList& points, double voxel_m) {
  // Open-addressing hash of voxel keys (21 bits per axis, +-200 km at 0.2 m), accumulating
  // centroids; output follows first-seen order, so the result is deterministic.
  struct Slot {
    uint64_t key = 0;  // 0 = empty (keys are offset so that none is 0)
    uint32_t index = 0;
  };
  size_t capacity = 16;
  while (capacity < 2 * points.size()) capacity <<= 1;
  std::vector<Slot> table(capacity);
  std::vector<Eigen::Vector3d> sum;
  std::vector<uint32_t> count;
  sum.reserve(points.size() / 2);
  count.reserve(points.size() / 2);
  const double inv = 1.0 / voxel_m;
  constexpr int64_t kOffset = int64_t{1} << 20;
  constexpr uint64_t kMask = (uint64_t{1} << 21) - 1;
  for (const Eigen::Vector3f& p : points) {
    const int64_t ix = static_cast<int64_t>(std::floor(p.x() * inv)) + kOffset;
    const int64_t iy = static_cast<int64_t>(std::floor(p.y() * inv)) + kOffset;
    const int64_t iz = static_cast<int64_t>(std::floor(p.z() * inv)) + kOffset;
    const uint64_t key = ((static_cast<uint64_t>(ix) & kMask) << 42) |
                         ((static_cast<uint64_t>(iy) & kMask) << 21) |
                         (static_cast<uint64_t>(iz) & kMask) | (uint64_t{1} << 63);
    size_t h = (key * 0x9E3779B97F4A7C15ull) >> 20;
    while (true) {
      Slot& s = table[h & (capacity - 1)];
      if (s.key == 0) {
        s.key = key;
        s.index = static_cast<uint32_t>(sum.size());
        sum.push_back(p.cast<double>());
        count.push_back(1);
        break;
      }
      if (s.key == key) {
        sum[s.index] += p.cast<double>();
        ++count[s.index];
        break;
      }
      ++h;
    }
  }
  PointList out(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) out[i] = (sum[i] / count[i]).cast<float>();
  return out;
}

bool deskew(PointList& points, const std::vector<float>& time_s, const Eigen::Vector3d& v,
            const Eigen::Vector3d& w) {
  if (time_s.empty()) return true;
  if (time_s.size() != points.size()) return false;
  for (size_t i = 0; i < points.size(); ++i) {
    const double t = time_s[i];
    if (!std::isfinite(t)) continue;
    // Pose of the sensor at time t relative to the stamp: rotation w*t, translation v*t.
    const Eigen::Vector3d rv = w * t;
    const double angle = rv.norm();
    const Eigen::Matrix3d R = angle > 1e-12
                                  ? Eigen::AngleAxisd(angle, rv / angle).toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    points[i] = (R * points[i].cast<double>() + v * t).cast<float>();
  }
  return true;
}

}  // namespace gmm_localization
