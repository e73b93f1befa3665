#include "gmm_localization/core/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gmm_localization {
namespace {

constexpr double kHalfLog2Pi = 0.91893853320467274178;
// Heights beyond this are treated as corrupt input and ignored when sizing a chunk's z range.
constexpr double kMaxAbsHeightM = 1.0e4;

int32_t floorBin(double z, double step) { return static_cast<int32_t>(std::floor(z / step)); }

/// z range and the mixtures of the (C + R)^2 cells a chunk's layers read.
struct ChunkInput {
  int extent = 0;                                 // C + R cells per axis
  std::vector<const GaussianMixture1D*> mixture;  // extent^2, nullptr where no data
  int32_t zb_lo = 0;
  int32_t zb_hi = -1;  // inclusive; zb_hi < zb_lo: nothing above the floor
};

ChunkInput gatherInput(const GmmMap& map, const MapChunk& chunk, int reach, double z_step,
                       double ll_floor) {
  ChunkInput in;
  in.extent = chunk.cells() + reach;
  in.mixture.assign(static_cast<size_t>(in.extent) * in.extent, nullptr);
  double z_min = std::numeric_limits<double>::infinity();
  double z_max = -std::numeric_limits<double>::infinity();
  const CellIndex o = chunk.origin();
  for (int ey = 0; ey < in.extent; ++ey) {
    for (int ex = 0; ex < in.extent; ++ex) {
      const GaussianMixture1D* g = map.cell({o.x + ex, o.y + ey});
      if (g == nullptr || g->empty()) continue;
      const auto range = aboveFloorRange(*g, ll_floor);
      if (!(range.first <= range.second)) continue;
      in.mixture[static_cast<size_t>(ey) * in.extent + ex] = g;
      z_min = std::min(z_min, std::max(range.first, -kMaxAbsHeightM));
      z_max = std::max(z_max, std::min(range.second, kMaxAbsHeightM));
    }
  }
  if (z_min <= z_max) {
    in.zb_lo = floorBin(z_min, z_step);
    in.zb_hi = floorBin(z_max, z_step);
  }
  return in;
}

/// One working layer over the extended area, [z][y][x] with stride extent.
struct WorkLayer {
  int32_t z_lo = 0;
  int32_t nz = 0;
  std::vector<uint8_t> v;
};

/// Layer k from layer k-1 (Fig. 4): max over the four blocks of half size at offsets
/// {0, h} x {0, h}, then over pairs of z bins when coarsening. Valid for cells whose block
/// stays inside the extended area, which includes the chunk itself.
WorkLayer nextLayer(const WorkLayer& prev, int extent, int h, bool coarsen_z) {
  // coarsen_z: this layer halves the z resolution of the previous one.
  const size_t plane = static_cast<size_t>(extent) * extent;
  const int valid = extent - h;  // cells whose +h neighbour exists
  std::vector<uint8_t> xy(prev.v.size(), 0);
  for (int32_t z = 0; z < prev.nz; ++z) {
    const uint8_t* src = prev.v.data() + z * plane;
    uint8_t* dst = xy.data() + z * plane;
    for (int y = 0; y < valid; ++y) {
      const uint8_t* r0 = src + static_cast<size_t>(y) * extent;
      const uint8_t* r1 = r0 + static_cast<size_t>(h) * extent;
      uint8_t* out = dst + static_cast<size_t>(y) * extent;
      for (int x = 0; x < valid; ++x) {
        out[x] = std::max(std::max(r0[x], r0[x + h]), std::max(r1[x], r1[x + h]));
      }
    }
  }
  WorkLayer next;
  if (!coarsen_z) {
    next.z_lo = prev.z_lo;
    next.nz = prev.nz;
    next.v = std::move(xy);
    return next;
  }
  const int32_t z_hi = prev.z_lo + prev.nz - 1;
  next.z_lo = prev.z_lo >> 1;
  next.nz = prev.nz > 0 ? (z_hi >> 1) - next.z_lo + 1 : 0;
  next.v.assign(static_cast<size_t>(next.nz) * plane, 0);
  for (int32_t zp = 0; zp < prev.nz; ++zp) {
    const int32_t zn = ((prev.z_lo + zp) >> 1) - next.z_lo;
    const uint8_t* src = xy.data() + zp * plane;
    uint8_t* dst = next.v.data() + zn * plane;
    for (size_t i = 0; i < plane; ++i) dst[i] = std::max(dst[i], src[i]);
  }
  return next;
}

}  // namespace

std::vector<double> mixtureModes(const GaussianMixture1D& g) { return g.modes(); }

std::pair<double, double> aboveFloorRange(const GaussianMixture1D& g, double ll_floor) {
  // p(z) <= K max_j w_j N_j(z), so log p(z) >= floor needs log(w_j N_j(z)) >= floor - log K
  // for some j: |z - mu_j| <= sigma_j sqrt(2 (log w_j - log sigma_j - log sqrt(2 pi) - floor
  // + log K)).
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  const double log_k = std::log(static_cast<double>(std::max(1, g.size())));
  for (int j = 0; j < g.size(); ++j) {
    const GaussianComponent& c = g.component(j);
    if (!(c.weight > 0.f && c.sigma_m > 0.f)) continue;
    const double slack = std::log(c.weight) - std::log(c.sigma_m) - kHalfLog2Pi - ll_floor + log_k;
    if (slack < 0.0) continue;
    const double d = c.sigma_m * std::sqrt(2.0 * slack);
    lo = std::min(lo, c.mean_m - d);
    hi = std::max(hi, c.mean_m + d);
  }
  return {lo, hi};
}

void rasterizeCell(const GaussianMixture1D& g, int32_t zb_lo, int32_t nz, double z_step_m,
                   const ScoreQuantizer& quantizer, uint8_t* out, size_t stride) {
  if (g.empty() || nz <= 0) return;
  const auto range = aboveFloorRange(g, quantizer.floor());
  if (!(range.first <= range.second)) return;
  const int32_t b0 = std::max(zb_lo, floorBin(std::max(range.first, -kMaxAbsHeightM), z_step_m));
  const int32_t b1 =
      std::min(zb_lo + nz - 1, floorBin(std::min(range.second, kMaxAbsHeightM), z_step_m));
  if (b0 > b1) return;
  const std::vector<double> modes = g.modes();
  double ll_lo = g.logLikelihood(b0 * z_step_m);
  for (int32_t b = b0; b <= b1; ++b) {
    const double z_lo = b * z_step_m;
    const double z_hi = (b + 1) * z_step_m;
    const double ll_hi = g.logLikelihood(z_hi);
    double best = std::max(ll_lo, ll_hi);
    for (double m : modes) {
      if (m > z_lo && m < z_hi) best = std::max(best, g.logLikelihood(m));
    }
    out[static_cast<size_t>(b - zb_lo) * stride] = quantizer.quantize(best);
    ll_lo = ll_hi;
  }
}

Result<MapChunkConstPtr> rasterizeChunk(const GmmMap& map, ChunkId id,
                                        const RasterOptions& options) {
  const std::string invalid = options.validate();
  if (!invalid.empty()) return Result<MapChunkConstPtr>::failure("raster options: " + invalid);
  auto chunk = std::make_shared<MapChunk>(id, options.chunk_shift);
  const int cells = chunk->cells();
  const int reach = (1 << options.num_layers) - 1;
  const ChunkInput in = gatherInput(map, *chunk, reach, options.z_step_m, options.ll_floor);
  const int extent = in.extent;
  const size_t plane = static_cast<size_t>(extent) * extent;
  const size_t out_plane = static_cast<size_t>(cells) * cells;
  const ScoreQuantizer quantizer(options);

  // Base layer over the extended area.
  WorkLayer work;
  work.z_lo = in.zb_lo;
  work.nz = in.zb_hi >= in.zb_lo ? in.zb_hi - in.zb_lo + 1 : 0;
  work.v.assign(static_cast<size_t>(work.nz) * plane, 0);
  for (size_t i = 0; i < plane && work.nz > 0; ++i) {
    if (in.mixture[i] != nullptr) {
      rasterizeCell(*in.mixture[i], work.z_lo, work.nz, options.z_step_m, quantizer,
                    work.v.data() + i, plane);
    }
  }

  // Crop each layer to the chunk and append it to one buffer.
  auto storage = std::make_shared<std::vector<uint8_t>>();
  std::vector<std::pair<RasterLayer, size_t>> placed;  // layer, offset into storage
  auto crop = [&](const WorkLayer& w, int z_shift) {
    RasterLayer L;
    L.z_lo = w.z_lo;
    L.nz = w.nz;
    L.z_shift = z_shift;
    const size_t offset = storage->size();
    storage->resize(offset + static_cast<size_t>(w.nz) * out_plane);
    for (int32_t z = 0; z < w.nz; ++z) {
      for (int y = 0; y < cells; ++y) {
        const uint8_t* src = w.v.data() + z * plane + static_cast<size_t>(y) * extent;
        std::copy(src, src + cells, storage->data() + offset + z * out_plane + y * cells);
      }
    }
    placed.emplace_back(L, offset);
  };
  crop(work, 0);
  for (int k = 1; k <= options.num_layers; ++k) {
    work = nextLayer(work, extent, 1 << (k - 1), options.zShift(k) > options.zShift(k - 1));
    crop(work, options.zShift(k));
  }
  std::vector<RasterLayer> layers;
  for (auto& [L, offset] : placed) {
    L.data = storage->data() + offset;
    layers.push_back(L);
  }
  chunk->setLayers(std::move(layers), storage);

  std::vector<GaussianMixture1D> mixtures(out_plane);
  const CellIndex o = chunk->origin();
  for (int y = 0; y < cells; ++y) {
    for (int x = 0; x < cells; ++x) {
      const GaussianMixture1D* g = map.cell({o.x + x, o.y + y});
      if (g != nullptr) mixtures[static_cast<size_t>(y) * cells + x] = *g;
    }
  }
  chunk->setMixtures(std::move(mixtures));
  return MapChunkConstPtr(chunk);
}

}  // namespace gmm_localization
