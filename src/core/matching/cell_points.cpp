#include "cell_points.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace gmm_localization {
namespace search_detail {
namespace {

/// Sorts by (gy, gx, zb). A scan's cells span a few hundred rows, columns and z bins, so the
/// three fit a packed key of under 64 bits, sorted by a byte-wise LSD radix sort (a few
/// linear passes instead of n log n comparisons: this runs once per heading). Falls back to
/// a comparison sort when the ranges do not fit.
void sortCellPoints(std::vector<CellPoint>& pts) {
  if (pts.size() < 2) return;
  int32_t lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  for (const CellPoint& p : pts) {
    const int32_t v[3] = {p.gy, p.gx, p.zb};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
  }
  int bits[3];
  for (int k = 0; k < 3; ++k) {
    const uint64_t range = static_cast<uint64_t>(int64_t{hi[k]} - lo[k]);
    bits[k] = 0;
    while (bits[k] < 63 && (range >> bits[k]) != 0) ++bits[k];
  }
  const int total = bits[0] + bits[1] + bits[2];
  if (total > 62) {
    std::sort(pts.begin(), pts.end(), [](const CellPoint& a, const CellPoint& b) {
      if (a.gy != b.gy) return a.gy < b.gy;
      if (a.gx != b.gx) return a.gx < b.gx;
      return a.zb < b.zb;
    });
    return;
  }
  std::vector<uint64_t> keys(pts.size()), tmp(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const CellPoint& p = pts[i];
    keys[i] = (static_cast<uint64_t>(int64_t{p.gy} - lo[0]) << (bits[1] + bits[2])) |
              (static_cast<uint64_t>(int64_t{p.gx} - lo[1]) << bits[2]) |
              static_cast<uint64_t>(int64_t{p.zb} - lo[2]);
  }
  for (int shift = 0; shift < total; shift += 8) {
    size_t count[257] = {0};
    for (uint64_t k : keys) ++count[((k >> shift) & 0xff) + 1];
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (uint64_t k : keys) tmp[count[(k >> shift) & 0xff]++] = k;
    keys.swap(tmp);
  }
  const uint64_t mask_x = bits[1] > 0 ? ((uint64_t{1} << bits[1]) - 1) : 0;
  const uint64_t mask_z = bits[2] > 0 ? ((uint64_t{1} << bits[2]) - 1) : 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const uint64_t k = keys[i];
    pts[i].zb = static_cast<int32_t>(int64_t{lo[2]} + static_cast<int64_t>(k & mask_z));
    pts[i].gx =
        static_cast<int32_t>(int64_t{lo[1]} + static_cast<int64_t>((k >> bits[2]) & mask_x));
    pts[i].gy =
        static_cast<int32_t>(int64_t{lo[0]} + static_cast<int64_t>(k >> (bits[1] + bits[2])));
    pts[i].count = 1;
  }
}

}  // namespace

RotatedPoints rotatePoints(const ChunkMap& map, const PointList& points, const SearchWindow& window,
                           double z0_m, TaskPool* pool) {
  const MapGeometry& g = map.geometry();
  RotatedPoints r;
  std::vector<std::vector<CellPoint>>& rotated = r.per_heading;
  rotated.resize(static_cast<size_t>(window.sizeH()));
  int64_t gx_min = std::numeric_limits<int64_t>::max(), gy_min = gx_min;
  int64_t gx_max = std::numeric_limits<int64_t>::min(), gy_max = gx_max;
  const Pose6& prior = window.prior;
  // Heights do not change with heading: bin them once.
  std::vector<int32_t> z_bins(points.size());
  for (size_t i = 0; i < points.size(); ++i) z_bins[i] = map.zBin(z0_m + points[i].z());
  // Headings in parallel, each with its own extent (combined after, in heading order).
  struct Extent {
    int64_t gx_min, gy_min, gx_max, gy_max;
  };
  std::vector<Extent> extents(static_cast<size_t>(window.sizeH()),
                              {gx_min, gy_min, gx_max, gy_max});
  parallelFor(pool, window.sizeH(), [&](int j) {
    Extent& e = extents[static_cast<size_t>(j)];
    const double yaw = prior.yaw + (j - window.half_h) * window.heading_step_rad;
    const double c = std::cos(yaw), s = std::sin(yaw);
    std::vector<CellPoint>& out = rotated[j];
    out.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3f& q = points[i];
      const double x = prior.x + c * q.x() - s * q.y();
      const double y = prior.y + s * q.x() + c * q.y();
      const CellIndex cell = g.cellAt(x, y);
      out[i] = {static_cast<int32_t>(cell.x - window.half_x),
                static_cast<int32_t>(cell.y - window.half_y), z_bins[i], 1u};
    }
    // Sort by (row, column, z bin): the tables store each cell's z span contiguously and the
    // cells row by row, so this order reads them almost sequentially. Then merge points that
    // share a cell and bin.
    sortCellPoints(out);
    size_t w = 0;
    for (size_t i = 0; i < out.size(); ++i) {
      if (w > 0 && out[w - 1].zb == out[i].zb && out[w - 1].gy == out[i].gy &&
          out[w - 1].gx == out[i].gx) {
        out[w - 1].count += out[i].count;
      } else {
        out[w++] = out[i];
      }
    }
    out.resize(w);
    for (const CellPoint& p : out) {
      e.gx_min = std::min<int64_t>(e.gx_min, p.gx);
      e.gx_max = std::max<int64_t>(e.gx_max, p.gx);
      e.gy_min = std::min<int64_t>(e.gy_min, p.gy);
      e.gy_max = std::max<int64_t>(e.gy_max, p.gy);
    }
  });
  for (const Extent& e : extents) {
    gx_min = std::min(gx_min, e.gx_min);
    gx_max = std::max(gx_max, e.gx_max);
    gy_min = std::min(gy_min, e.gy_min);
    gy_max = std::max(gy_max, e.gy_max);
  }
  r.gx_min = gx_min;
  r.gy_min = gy_min;
  r.gx_max = gx_max;
  r.gy_max = gy_max;
  return r;
}

}  // namespace search_detail
}  // namespace gmm_localization
