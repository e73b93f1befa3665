#include "gmm_localization/core/matching/search_problem.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace gmm_localization {

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

SearchWindow SearchWindow::fromExtent(const Pose6& prior, double half_extent_x_m,
                                      double half_extent_y_m, double half_heading_rad,
                                      double heading_step_rad, double resolution_m) {
  SearchWindow w;
  w.prior = prior;
  w.half_x = static_cast<int>(std::ceil(half_extent_x_m / resolution_m - 1e-9));
  w.half_y = static_cast<int>(std::ceil(half_extent_y_m / resolution_m - 1e-9));
  w.heading_step_rad = heading_step_rad;
  w.half_h = heading_step_rad > 0.0
                 ? static_cast<int>(std::ceil(half_heading_rad / heading_step_rad - 1e-9))
                 : 0;
  return w;
}

std::string SearchWindow::validate() const {
  const Pose6& p = prior;
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
        std::isfinite(p.pitch) && std::isfinite(p.yaw))) {
    return "prior pose is not finite";
  }
  if (half_x < 0 || half_y < 0 || half_h < 0 || half_x > 4096 || half_y > 4096 || half_h > 2048) {
    return "window half sizes (" + std::to_string(half_x) + ", " + std::to_string(half_y) +
           " cells, " + std::to_string(half_h) + " headings) must be in [0, 4096] / [0, 2048]";
  }
  if (half_h > 0 && !(heading_step_rad > 0.0 && heading_step_rad < 1.0)) {
    return "heading_step_rad=" + std::to_string(heading_step_rad) + " must be in (0, 1)";
  }
  return {};
}

RasterWindow::RasterWindow(const ChunkMap& map, int64_t gx_min, int64_t gy_min, int64_t gx_max,
                           int64_t gy_max) {
  shift_ = map.options().chunk_shift;
  mask_ = (int64_t{1} << shift_) - 1;
  cx0_ = gx_min >> shift_;
  cy0_ = gy_min >> shift_;
  w_ = (gx_max >> shift_) - cx0_ + 1;
  h_ = (gy_max >> shift_) - cy0_ + 1;
  grid_.assign(static_cast<size_t>(w_ * h_), nullptr);
  for (int64_t cy = 0; cy < h_; ++cy) {
    for (int64_t cx = 0; cx < w_; ++cx) {
      MapChunkConstPtr c =
          map.find({static_cast<int32_t>(cx + cx0_), static_cast<int32_t>(cy + cy0_)});
      grid_[static_cast<size_t>(cy * w_ + cx)] = c.get();  // the ChunkMap keeps it alive
    }
  }
}

uint8_t RasterWindow::neighbourBound(int layer, int64_t gx, int64_t gy, int64_t size,
                                     int32_t zb) const {
  // The first cells of the next chunks: (chunk index + 1) x cells (no shift of a negative).
  const int64_t cells = int64_t{1} << shift_;
  const int64_t nx = ((gx >> shift_) + 1) * cells;
  const int64_t ny = ((gy >> shift_) + 1) * cells;
  const bool right = nx < gx + size, up = ny < gy + size;
  uint8_t v = 0;
  if (right) v = std::max(v, value(layer, nx, gy, zb));
  if (up) v = std::max(v, value(layer, gx, ny, zb));
  if (right && up) v = std::max(v, value(layer, nx, ny, zb));
  return v;
}

size_t RasterWindow::chunksPresent() const {
  return static_cast<size_t>(
      std::count_if(grid_.begin(), grid_.end(), [](const MapChunk* c) { return c != nullptr; }));
}

Result<SearchProblem> SearchProblem::create(const ChunkMap& map, const PointList& points,
                                            const SearchWindow& window, TaskPool* pool) {
  const std::string invalid = window.validate();
  if (!invalid.empty()) return Result<SearchProblem>::failure("search window: " + invalid);
  if (points.empty()) return Result<SearchProblem>::failure("no points left to match");

  const MapGeometry& g = map.geometry();
  const RasterOptions& ro = map.options();
  std::vector<std::vector<CellPoint>> rotated(window.sizeH());
  int64_t gx_min = std::numeric_limits<int64_t>::max(), gy_min = gx_min;
  int64_t gx_max = std::numeric_limits<int64_t>::min(), gy_max = gx_max;
  const Pose6& prior = window.prior;
  // Heights do not change with heading: bin them once.
  std::vector<int32_t> z_bins(points.size());
  for (size_t i = 0; i < points.size(); ++i) z_bins[i] = map.zBin(prior.z + points[i].z());
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

  // The coarsest layer, searched exhaustively (Algorithm 3), is the smallest that covers the
  // window in a 4 x 4 node grid per heading, or in a 2 x 2 grid if that is no coarser than
  // layer kPruningLayer. Layers above it (blocks over 16 x 16 cells) bound so loosely that
  // nearly every node is expanded anyway, and a best-first descent from them jumps between
  // headings, out of cache, while the exhaustive top layer is scored heading by heading, four
  // nodes per pass. Measured on the simulated Downtown scans: paper window (125 cells) from
  // layer 5, 4 x 4, search 53-58 ms against 67-72 ms from layer 6, 2 x 2, and 99 ms from
  // layer 4, 8 x 8; tracking window (21 cells) from layer 4, 2 x 2, 8.0 against 9.0 ms from
  // layer 3, 3 x 3.
  constexpr int kPruningLayer = 4;
  const int size = std::max(window.sizeX(), window.sizeY());
  auto covering = [&](int grid) {
    int layer = 0;
    while (layer < ro.num_layers && grid * (1 << layer) < size) ++layer;
    return layer;
  };
  const int top = std::max(covering(4), std::min(covering(2), kPruningLayer));
  // Node blocks of layer `top` starting inside the window reach 2^top - 1 cells beyond it.
  const int64_t reach = (int64_t{1} << top) - 1;
  RasterWindow raster(map, gx_min, gy_min, gx_max + window.sizeX() - 1 + reach,
                      gy_max + window.sizeY() - 1 + reach);
  if (raster.chunksPresent() == 0) {
    return Result<SearchProblem>::failure(
        "off the map: no rasterized map chunk under the scan anywhere in the search window");
  }
  SearchProblem problem(map, window, std::move(raster));
  problem.rotated_ = std::move(rotated);
  problem.scan_points_ = static_cast<int64_t>(points.size());
  problem.top_layer_ = top;
  return problem;
}

int64_t SearchProblem::score(int heading_index, int layer, int tx, int ty) const {
  int64_t sum = 0;
  const int shift = raster_.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  for (const CellPoint& p : rotated_[heading_index]) {
    const int64_t gx = static_cast<int64_t>(p.gx) + tx;
    const int64_t gy = static_cast<int64_t>(p.gy) + ty;
    const MapChunk* c = raster_.chunk(gx, gy);
    const uint8_t v = c != nullptr ? c->value(layer, p.zb, static_cast<int>(gx & mask),
                                              static_cast<int>(gy & mask))
                                   : raster_.blockBound(layer, gx, gy, p.zb);
    sum += static_cast<int64_t>(p.count) * v;
  }
  return sum;
}

void SearchProblem::scoreQuad(int heading_index, int layer, int tx, int ty, int h,
                              int64_t out[4]) const {
  int64_t s00 = 0, s10 = 0, s01 = 0, s11 = 0;
  const int shift = raster_.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  const size_t dy = static_cast<size_t>(h) << shift;
  // Points come sorted by row and column, so consecutive points mostly share a chunk: keep the
  // last chunk's layer at hand.
  int64_t cached_cx = INT64_MIN, cached_cy = INT64_MIN;
  const RasterLayer* L = nullptr;
  for (const CellPoint& p : rotated_[heading_index]) {
    const int64_t gx = static_cast<int64_t>(p.gx) + tx;
    const int64_t gy = static_cast<int64_t>(p.gy) + ty;
    const int64_t lx = gx & mask, ly = gy & mask;
    const int64_t count = p.count;
    if (lx + h <= mask && ly + h <= mask) {
      // All four cells lie in one chunk: four span reads.
      if ((gx >> shift) != cached_cx || (gy >> shift) != cached_cy) {
        cached_cx = gx >> shift;
        cached_cy = gy >> shift;
        const MapChunk* c = raster_.chunk(gx, gy);
        L = c != nullptr ? &c->layer(layer) : nullptr;
      }
      if (L == nullptr) {  // not loaded: the blocks may still reach into loaded neighbours
        if (layer == 0) continue;
        s00 += count * raster_.blockBound(layer, gx, gy, p.zb);
        s10 += count * raster_.blockBound(layer, gx + h, gy, p.zb);
        s01 += count * raster_.blockBound(layer, gx, gy + h, p.zb);
        s11 += count * raster_.blockBound(layer, gx + h, gy + h, p.zb);
        continue;
      }
      const size_t i = (static_cast<size_t>(ly) << shift) + static_cast<size_t>(lx);
      s00 += count * MapChunk::spanValue(*L, i, p.zb);
      s10 += count * MapChunk::spanValue(*L, i + h, p.zb);
      s01 += count * MapChunk::spanValue(*L, i + dy, p.zb);
      s11 += count * MapChunk::spanValue(*L, i + dy + h, p.zb);
    } else {
      s00 += count * raster_.blockBound(layer, gx, gy, p.zb);
      s10 += count * raster_.blockBound(layer, gx + h, gy, p.zb);
      s01 += count * raster_.blockBound(layer, gx, gy + h, p.zb);
      s11 += count * raster_.blockBound(layer, gx + h, gy + h, p.zb);
    }
  }
  out[0] = s00;
  out[1] = s10;
  out[2] = s01;
  out[3] = s11;
}

int64_t SearchProblem::scoreBlock(int heading_index, int tx0, int ty0, int nx, int ny,
                                  std::vector<int64_t>& out, int point_stride) const {
  std::vector<int32_t> acc(static_cast<size_t>(nx) * ny, 0);
  const int shift = raster_.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  const std::vector<CellPoint>& pts = rotated_[heading_index];
  const size_t stride = static_cast<size_t>(std::max(1, point_stride));
  int64_t scored = 0;
  for (size_t k = 0; k < pts.size(); k += stride) {
    const CellPoint& p = pts[k];
    const int32_t count = static_cast<int32_t>(p.count);
    scored += count;
    for (int r = 0; r < ny; ++r) {
      const int64_t gy = static_cast<int64_t>(p.gy) + ty0 + r;
      int32_t* row = acc.data() + static_cast<size_t>(r) * nx;
      int64_t gx = static_cast<int64_t>(p.gx) + tx0;
      int i = 0;
      while (i < nx) {
        // One segment: the part of the row inside one chunk (consecutive cell spans).
        const int seg = static_cast<int>(std::min<int64_t>(nx - i, mask + 1 - (gx & mask)));
        const MapChunk* c = raster_.chunk(gx, gy);
        if (c != nullptr) {
          const RasterLayer& L = c->layer(0);
          const size_t first =
              (static_cast<size_t>(gy & mask) << shift) + static_cast<size_t>(gx & mask);
          for (int k = 0; k < seg; ++k)
            row[i + k] += count * MapChunk::spanValue(L, first + k, p.zb);
        }
        i += seg;
        gx += seg;
      }
    }
  }
  out.assign(acc.begin(), acc.end());
  return scored;
}

Pose6 SearchProblem::pose(int heading_index, int tx, int ty) const {
  Pose6 p = window_.prior;
  const double res = map_->geometry().resolution_m;
  p.x += (tx - window_.half_x) * res;
  p.y += (ty - window_.half_y) * res;
  p.yaw += (heading_index - window_.half_h) * window_.heading_step_rad;
  return p;
}

}  // namespace gmm_localization
