#include "gmm_localization/core/matching/search_problem.h"

#include "cell_points.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace gmm_localization {

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

std::string channelCompatibility(const ChunkMap& first, const ChunkMap& second) {
  const MapGeometry& a = first.geometry();
  const MapGeometry& b = second.geometry();
  const RasterOptions& ra = first.options();
  const RasterOptions& rb = second.options();
  auto num = [](double v) { return std::to_string(v); };
  if (a.resolution_m != b.resolution_m) {
    return "the maps differ in resolution (" + num(a.resolution_m) + " against " +
           num(b.resolution_m) + " m): their cells must coincide";
  }
  if (a.origin_x_m != b.origin_x_m || a.origin_y_m != b.origin_y_m) {
    return "the maps differ in origin ((" + num(a.origin_x_m) + ", " + num(a.origin_y_m) +
           ") against (" + num(b.origin_x_m) + ", " + num(b.origin_y_m) +
           ") m): their cells must coincide";
  }
  if (ra.chunk_shift != rb.chunk_shift || ra.num_layers != rb.num_layers) {
    return "the maps differ in chunk geometry (chunk_shift " + std::to_string(ra.chunk_shift) +
           " against " + std::to_string(rb.chunk_shift) + ", num_layers " +
           std::to_string(ra.num_layers) + " against " + std::to_string(rb.num_layers) + ")";
  }
  if (ra.ll_floor != rb.ll_floor || ra.ll_ceiling != rb.ll_ceiling) {
    return "the maps differ in score quantization (ll_floor, ll_ceiling): their table values "
           "would not add up to a log-likelihood";
  }
  return {};
}

Result<SearchProblem> SearchProblem::create(const ChunkMap& map, const PointList& points,
                                            const SearchWindow& window, TaskPool* pool,
                                            const SecondChannel* second) {
  using R = Result<SearchProblem>;
  const std::string invalid = window.validate();
  if (!invalid.empty()) return R::failure("search window: " + invalid);
  if (points.empty()) return R::failure("no points left to match");
  if (second != nullptr) {
    if (second->map == nullptr || second->points == nullptr) {
      return R::failure("second channel: no map or no points given");
    }
    const std::string incompatible = channelCompatibility(map, *second->map);
    if (!incompatible.empty()) return R::failure("second channel: " + incompatible);
    if (second->points->empty()) return R::failure("second channel: no points left to match");
  }
  const RasterOptions& ro = map.options();
  // Heights of the first channel are relative to the prior's; the second's are absolute.
  std::vector<search_detail::RotatedPoints> rotated;
  rotated.push_back(search_detail::rotatePoints(map, points, window, window.prior.z, pool));
  if (second != nullptr) {
    rotated.push_back(
        search_detail::rotatePoints(*second->map, *second->points, window, 0.0, pool));
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
  SearchProblem problem(map, window);
  const ChunkMap* maps[2] = {&map, second != nullptr ? second->map : nullptr};
  const PointList* lists[2] = {&points, second != nullptr ? second->points : nullptr};
  for (size_t c = 0; c < rotated.size(); ++c) {
    const search_detail::RotatedPoints& r = rotated[c];
    RasterWindow raster(*maps[c], r.gx_min, r.gy_min, r.gx_max + window.sizeX() - 1 + reach,
                        r.gy_max + window.sizeY() - 1 + reach);
    if (raster.chunksPresent() == 0) {
      return R::failure(std::string(c == 0 ? "off the map" : "off the second channel's map") +
                        ": no rasterized map chunk under the scan anywhere in the search window");
    }
    problem.channels_.push_back({maps[c], std::move(raster), std::move(rotated[c].per_heading),
                                 static_cast<int64_t>(lists[c]->size())});
    problem.scan_points_ += static_cast<int64_t>(lists[c]->size());
  }
  problem.top_layer_ = top;
  return problem;
}

int64_t SearchProblem::score(int heading_index, int layer, int tx, int ty) const {
  int64_t sum = 0;
  for (const Channel& ch : channels_) sum += channelScore(ch, heading_index, layer, tx, ty);
  return sum;
}

int64_t SearchProblem::channelScore(const Channel& ch, int heading_index, int layer, int tx,
                                    int ty) {
  const RasterWindow& raster = ch.raster;
  int64_t sum = 0;
  const int shift = raster.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  for (const CellPoint& p : ch.rotated[heading_index]) {
    const int64_t gx = static_cast<int64_t>(p.gx) + tx;
    const int64_t gy = static_cast<int64_t>(p.gy) + ty;
    const MapChunk* c = raster.chunk(gx, gy);
    const uint8_t v = c != nullptr ? c->value(layer, p.zb, static_cast<int>(gx & mask),
                                              static_cast<int>(gy & mask))
                                   : raster.blockBound(layer, gx, gy, p.zb);
    sum += static_cast<int64_t>(p.count) * v;
  }
  return sum;
}

void SearchProblem::scoreQuad(int heading_index, int layer, int tx, int ty, int h,
                              int64_t out[4]) const {
  out[0] = out[1] = out[2] = out[3] = 0;
  for (const Channel& ch : channels_) channelScoreQuad(ch, heading_index, layer, tx, ty, h, out);
}

void SearchProblem::channelScoreQuad(const Channel& ch, int heading_index, int layer, int tx,
                                     int ty, int h, int64_t out[4]) {
  const RasterWindow& raster = ch.raster;
  int64_t s00 = 0, s10 = 0, s01 = 0, s11 = 0;
  const int shift = raster.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  const size_t dy = static_cast<size_t>(h) << shift;
  // Points come sorted by row and column, so consecutive points mostly share a chunk: keep the
  // last chunk's layer at hand.
  int64_t cached_cx = INT64_MIN, cached_cy = INT64_MIN;
  const RasterLayer* L = nullptr;
  for (const CellPoint& p : ch.rotated[heading_index]) {
    const int64_t gx = static_cast<int64_t>(p.gx) + tx;
    const int64_t gy = static_cast<int64_t>(p.gy) + ty;
    const int64_t lx = gx & mask, ly = gy & mask;
    const int64_t count = p.count;
    if (lx + h <= mask && ly + h <= mask) {
      // All four cells lie in one chunk: four span reads.
      if ((gx >> shift) != cached_cx || (gy >> shift) != cached_cy) {
        cached_cx = gx >> shift;
        cached_cy = gy >> shift;
        const MapChunk* c = raster.chunk(gx, gy);
        L = c != nullptr ? &c->layer(layer) : nullptr;
      }
      if (L == nullptr) {  // not loaded: the blocks may still reach into loaded neighbours
        if (layer == 0) continue;
        s00 += count * raster.blockBound(layer, gx, gy, p.zb);
        s10 += count * raster.blockBound(layer, gx + h, gy, p.zb);
        s01 += count * raster.blockBound(layer, gx, gy + h, p.zb);
        s11 += count * raster.blockBound(layer, gx + h, gy + h, p.zb);
        continue;
      }
      const size_t i = (static_cast<size_t>(ly) << shift) + static_cast<size_t>(lx);
      s00 += count * MapChunk::spanValue(*L, i, p.zb);
      s10 += count * MapChunk::spanValue(*L, i + h, p.zb);
      s01 += count * MapChunk::spanValue(*L, i + dy, p.zb);
      s11 += count * MapChunk::spanValue(*L, i + dy + h, p.zb);
    } else {
      s00 += count * raster.blockBound(layer, gx, gy, p.zb);
      s10 += count * raster.blockBound(layer, gx + h, gy, p.zb);
      s01 += count * raster.blockBound(layer, gx, gy + h, p.zb);
      s11 += count * raster.blockBound(layer, gx + h, gy + h, p.zb);
    }
  }
  out[0] += s00;
  out[1] += s10;
  out[2] += s01;
  out[3] += s11;
}

int64_t SearchProblem::scoreBlock(int heading_index, int tx0, int ty0, int nx, int ny,
                                  std::vector<int64_t>& out, int point_stride) const {
  std::vector<int32_t> acc(static_cast<size_t>(nx) * ny, 0);
  int64_t scored = 0;
  for (const Channel& ch : channels_) {
    scored += channelScoreBlock(ch, heading_index, tx0, ty0, nx, ny, acc, point_stride);
  }
  out.assign(acc.begin(), acc.end());
  return scored;
}

int64_t SearchProblem::channelScoreBlock(const Channel& ch, int heading_index, int tx0, int ty0,
                                         int nx, int ny, std::vector<int32_t>& acc,
                                         int point_stride) {
  const RasterWindow& raster = ch.raster;
  const int shift = raster.shift();
  const int64_t mask = (int64_t{1} << shift) - 1;
  const std::vector<CellPoint>& pts = ch.rotated[heading_index];
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
        const MapChunk* c = raster.chunk(gx, gy);
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
  return scored;
}

int64_t SearchProblem::preparedPoints(int heading_index) const {
  int64_t n = 0;
  for (const Channel& ch : channels_) n += static_cast<int64_t>(ch.rotated[heading_index].size());
  return n;
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
