#include "gmm_localization/core/matching/scan_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/key_index.h"
#include "gmm_localization/core/map/map_geometry.h"

namespace gmm_localization {

namespace {
constexpr uint64_t kMask31 = (uint64_t{1} << 31) - 1;

/// Voxel centroids, accumulated point by point. Voxel keys of 21 bits per axis (+-200 km at
/// 0.2 m) are numbered in first-seen order, so the output order is deterministic. Each voxel
/// sums its points' float offsets from its first point (small numbers: no precision lost to large
/// coordinates) in one 28-byte record. Scans arrive ring by ring, so consecutive points often
/// share a voxel: the last key is checked before the table.
class VoxelAccumulator {
 public:
  VoxelAccumulator(double voxel_m, size_t expected_voxels)
      : inv_(1.0 / voxel_m), index_(expected_voxels) {
    sums_.reserve(expected_voxels);
  }

  /// The voxel key of p.
  uint64_t key(const Eigen::Vector3f& p) const {
    const int64_t fx = floorToInt(p.x() * inv_), fy = floorToInt(p.y() * inv_),
                  fz = floorToInt(p.z() * inv_);
    return ((static_cast<uint64_t>(fx + kOffset) & kMask) << 42) |
           ((static_cast<uint64_t>(fy + kOffset) & kMask) << 21) |
           (static_cast<uint64_t>(fz + kOffset) & kMask);
  }
  /// Asks the memory for the table slot of `key` (add() with it soon after finds it cached).
  void prefetch(uint64_t key) const { index_.prefetch(key); }
  void add(const Eigen::Vector3f& p) { add(p, key(p)); }
  /// Adds p, whose key() is `key`.
  void add(const Eigen::Vector3f& p, uint64_t key) {
    if (key != last_key_) {
      bool inserted = false;
      last_ = index_.insert(key, inserted);
      last_key_ = key;
      if (inserted) sums_.push_back({p, Eigen::Vector3f::Zero(), 0u});
    }
    Sum& s = sums_[last_];
    s.offsets += p - s.first;
    ++s.n;
  }

  PointList centroids() const {
    PointList out(sums_.size());
    for (size_t i = 0; i < sums_.size(); ++i) {
      const Sum& s = sums_[i];
      out[i] = s.first + s.offsets / static_cast<float>(s.n);
    }
    return out;
  }

 private:
  struct Sum {
    Eigen::Vector3f first;    ///< the voxel's first point
    Eigen::Vector3f offsets;  ///< sum of (point - first)
    uint32_t n;
  };
  static constexpr int64_t kOffset = int64_t{1} << 20;
  static constexpr uint64_t kMask = (uint64_t{1} << 21) - 1;

  double inv_;
  KeyIndex index_;
  std::vector<Sum> sums_;
  uint64_t last_key_ = ~uint64_t{0};
  uint32_t last_ = 0;
};
}  // namespace

std::string ScanFilterOptions::validate() const {
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m)) {
    return "min_range_m=" + std::to_string(min_range_m) +
           ", max_range_m=" + std::to_string(max_range_m) + ": need 0 <= min_range_m < max_range_m";
  }
  if (!(max_height_m > min_height_m)) {
    return "min_height_m=" + std::to_string(min_height_m) +
           " must be below max_height_m=" + std::to_string(max_height_m);
  }
  if (!(ground_share >= 0.0 && ground_share <= 1.0)) {
    return "ground_share=" + std::to_string(ground_share) + " must be in [0, 1]";
  }
  if (!(ground_cell_m > 0.0 && ground_band_m >= 0.0)) {
    return "ground_cell_m must be > 0 and ground_band_m >= 0";
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
  // One pass: level, filter, and (with voxel_m > 0) accumulate voxels without a copy of the
  // kept points.
  const bool voxelize = options.voxel_m > 0.0;
  // About one voxel in four points at 0.2 m on a four-sensor revolution: the table is not grown.
  VoxelAccumulator voxels(voxelize ? options.voxel_m : 1.0, voxelize ? base_points.size() / 4 : 0);
  PointList kept;
  if (!voxelize) kept.reserve(base_points.size());
  // In batches: first each point's levelled position and voxel key, the key's table slot
  // requested ahead (the voxels of consecutive points are scattered over a table larger than
  // the caches), then the voxels in point order (the same centroids, in the same order).
  constexpr size_t kBatch = 32;
  Eigen::Vector3f level_q[kBatch];
  uint64_t keys[kBatch];
  for (size_t first = 0; first < base_points.size(); first += kBatch) {
    const size_t count = std::min(kBatch, base_points.size() - first);
    size_t passed = 0;
    for (size_t k = 0; k < count; ++k) {
      const Eigen::Vector3f& p = base_points[first + k];
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
      level_q[passed] = q;
      if (voxelize) {
        keys[passed] = voxels.key(q);
        voxels.prefetch(keys[passed]);
      }
      ++passed;
    }
    for (size_t k = 0; k < passed; ++k) {
      if (voxelize) {
        voxels.add(level_q[k], keys[k]);
      } else {
        kept.push_back(level_q[k]);
      }
    }
  }
  out.voxels = voxelize ? voxels.centroids() : std::move(kept);
  if (options.max_points == 0 || out.voxels.size() <= options.max_points) {
    out.points = out.voxels;
    return out;
  }
  const std::vector<bool> ground =
      groundMask(out.voxels, options.ground_cell_m, options.ground_band_m);
  out.ground_voxels = static_cast<size_t>(std::count(ground.begin(), ground.end(), true));
  out.points = selectSearchPoints(out.voxels, ground, options.max_points, options.ground_share);
  return out;
}

std::vector<bool> groundMask(const PointList& pts, double cell_m, double band_m) {
  const double inv = 1.0 / cell_m;
  auto key = [inv](const Eigen::Vector3f& p) {  // 31 bits per axis, offset to be non-negative
    const uint64_t ix = static_cast<uint64_t>(floorToInt(p.x() * inv) + (int64_t{1} << 30));
    const uint64_t iy = static_cast<uint64_t>(floorToInt(p.y() * inv) + (int64_t{1} << 30));
    return ((ix & kMask31) << 31) | (iy & kMask31);
  };
  KeyIndex cells(pts.size() / 16);
  std::vector<float> lowest;
  std::vector<uint32_t> cell_of(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    bool inserted = false;
    const uint32_t c = cells.insert(key(pts[i]), inserted);
    if (inserted) {
      lowest.push_back(pts[i].z());
    } else {
      lowest[c] = std::min(lowest[c], pts[i].z());
    }
    cell_of[i] = c;
  }
  std::vector<bool> ground(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    ground[i] = pts[i].z() <= lowest[cell_of[i]] + static_cast<float>(band_m);
  }
  return ground;
}

PointList selectSearchPoints(const PointList& pts, const std::vector<bool>& ground,
                             size_t max_points, double ground_share) {
  PointList g, s;
  for (size_t i = 0; i < pts.size(); ++i) (ground[i] ? g : s).push_back(pts[i]);
  // Ground keeps its natural share of the selection, capped at ground_share; when structure
  // runs short, ground fills the rest.
  const double natural = static_cast<double>(g.size()) / std::max<size_t>(1, pts.size());
  const size_t g_want = std::min(
      g.size(), static_cast<size_t>(std::floor(std::min(natural, ground_share) * max_points)));
  const size_t n_s = std::min(s.size(), max_points - g_want);
  const size_t n_g = std::min(g.size(), max_points - n_s);
  PointList out;
  out.reserve(n_s + n_g);
  auto take = [&out](const PointList& from, size_t n) {
    const double stride = n > 0 ? static_cast<double>(from.size()) / n : 0.0;
    for (size_t i = 0; i < n; ++i) out.push_back(from[static_cast<size_t>(i * stride)]);
  };
  take(s, n_s);
  take(g, n_g);
  return out;
}

PointList voxelDownsample(const PointList& points, double voxel_m) {
  VoxelAccumulator voxels(voxel_m, points.size() / 8);
  for (const Eigen::Vector3f& p : points) voxels.add(p);
  return voxels.centroids();
}

namespace {
/// sin(a) and 1 - cos(a). Within one revolution's turn (|a| <= 0.5 rad) from their Taylor
/// series to a^13 and a^14 (the next terms are below 1e-16 of the values: as accurate as the
/// library's, and 1 - cos without the cancellation), else from std::sin and std::cos.
void sinAndVersine(double a, double* s, double* v) {
  if (std::abs(a) > 0.5) {
    *s = std::sin(a);
    *v = 1.0 - std::cos(a);
    return;
  }
  // Horner forms of a (1 - a^2/3! + a^4/5! - ...) and a^2 (1/2! - a^2/4! + a^4/6! - ...).
  const double a2 = a * a;
  *s = a * (1.0 +
            a2 * (-1.0 / 6 +
                  a2 * (1.0 / 120 + a2 * (-1.0 / 5040 + a2 * (1.0 / 362880 +
                                                              a2 * (-1.0 / 39916800 +
                                                                    a2 * (1.0 / 6227020800.0)))))));
  *v = a2 *
       (1.0 / 2 +
        a2 * (-1.0 / 24 +
              a2 * (1.0 / 720 + a2 * (-1.0 / 40320 +
                                      a2 * (1.0 / 3628800 + a2 * (-1.0 / 479001600 +
                                                                  a2 * (1.0 / 87178291200.0)))))));
}
}  // namespace

bool deskew(PointList& points, const std::vector<float>& time_s, const Eigen::Vector3d& v,
            const Eigen::Vector3d& w) {
  if (time_s.empty()) return true;
  if (time_s.size() != points.size()) return false;
  // Every point turns about the same axis k = w / |w|, by the angle |w| t: Rodrigues' formula
  // R p = p + sin(a) (k x p) + (1 - cos(a)) (k x (k x p)), with no rotation matrix per point.
  const double rate = w.norm();
  const bool turns = rate > 1e-12 && std::isfinite(rate);
  const Eigen::Vector3d k = turns ? Eigen::Vector3d(w / rate) : Eigen::Vector3d::UnitZ();
  for (size_t i = 0; i < points.size(); ++i) {
    const double t = time_s[i];
    if (!std::isfinite(t)) continue;
    // Pose of the sensor at time t relative to the stamp: rotation w*t, translation v*t.
    const Eigen::Vector3d p = points[i].cast<double>();
    Eigen::Vector3d q = p;
    if (turns) {
      double s, c;
      sinAndVersine(rate * t, &s, &c);
      const Eigen::Vector3d kp = k.cross(p);
      q += s * kp + c * k.cross(kp);
    }
    points[i] = (q + v * t).cast<float>();
  }
  return true;
}

}  // namespace gmm_localization
