#include "gmm_localization/core/raster/rasterizer.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

#include "gmm_localization/core/map/gaussian_mixture.h"
#include "gmm_localization/core/raster/chunk_reach.h"

namespace gmm_localization {
namespace {

// Heights beyond this are treated as corrupt input and ignored when sizing a chunk's z range.
constexpr double kMaxAbsRasterHeightM = 1.0e4;

int32_t floorBin(double z, double step) { return static_cast<int32_t>(std::floor(z / step)); }

/// z range and the mixtures of the (C + R)^2 cells a chunk's layers read (chunkReadCells).
struct ChunkInput {
  int extent = 0;                                 // C + R cells per axis
  std::vector<const GaussianMixture1D*> mixture;  // extent^2, nullptr where no data
  int32_t zb_lo = 0;
  int32_t zb_hi = -1;  // inclusive; zb_hi < zb_lo: nothing above the floor
};

ChunkInput gatherInput(const GmmMap& map, const CellRect& read, double z_step, double ll_floor) {
  ChunkInput in;
  in.extent = static_cast<int>(read.widthCells());  // the rule's rectangle is square
  in.mixture.assign(static_cast<size_t>(in.extent) * in.extent, nullptr);
  double z_min = std::numeric_limits<double>::infinity();
  double z_max = -std::numeric_limits<double>::infinity();
  const CellIndex o = read.lo;
  for (int ey = 0; ey < in.extent; ++ey) {
    for (int ex = 0; ex < in.extent; ++ex) {
      const GaussianMixture1D* g = map.cell({o.x + ex, o.y + ey});
      if (g == nullptr || g->empty()) continue;
      const auto range = aboveFloorRange(*g, ll_floor);
      if (!(range.first <= range.second)) continue;
      in.mixture[static_cast<size_t>(ey) * in.extent + ex] = g;
      z_min = std::min(z_min, std::max(range.first, -kMaxAbsRasterHeightM));
      z_max = std::max(z_max, std::min(range.second, kMaxAbsRasterHeightM));
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
  const int32_t b0 =
      std::max(zb_lo, floorBin(std::max(range.first, -kMaxAbsRasterHeightM), z_step_m));
  const int32_t b1 =
      std::min(zb_lo + nz - 1, floorBin(std::min(range.second, kMaxAbsRasterHeightM), z_step_m));
  if (b0 > b1) return;
  const std::vector<double> modes = g.modes();
  const PreparedMixture terms(g);  // the same function without a log per call
  double ll_lo = terms.logLikelihood(b0 * z_step_m);
  for (int32_t b = b0; b <= b1; ++b) {
    const double z_lo = b * z_step_m;
    const double z_hi = (b + 1) * z_step_m;
    const double ll_hi = terms.logLikelihood(z_hi);
    double best = std::max(ll_lo, ll_hi);
    for (double m : modes) {
      if (m > z_lo && m < z_hi) best = std::max(best, terms.logLikelihood(m));
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
  const ChunkInput in =
      gatherInput(map, chunkReadCells(id, options), options.z_step_m, options.ll_floor);
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

  // Crop each layer to the chunk and compress it into per-cell z spans.
  struct Storage {
    std::vector<uint32_t> spans;
    std::vector<uint8_t> values;
  };
  auto storage = std::make_shared<Storage>();
  struct Placed {
    int32_t z_shift;
    size_t spans_start, values_start, value_count;
  };
  std::vector<Placed> placed;
  std::vector<int32_t> lo(out_plane), hi(out_plane);
  auto compress = [&](const WorkLayer& w, int z_shift) {
    std::fill(lo.begin(), lo.end(), INT32_MAX);
    std::fill(hi.begin(), hi.end(), -1);
    for (int32_t z = 0; z < w.nz; ++z) {
      for (int y = 0; y < cells; ++y) {
        const uint8_t* row = w.v.data() + z * plane + static_cast<size_t>(y) * extent;
        for (int x = 0; x < cells; ++x) {
          if (row[x] != 0) {
            const size_t i = static_cast<size_t>(y) * cells + x;
            lo[i] = std::min(lo[i], z);
            hi[i] = z;
          }
        }
      }
    }
    Placed p{z_shift, storage->spans.size(), storage->values.size(), 0};
    uint32_t offset = 0;
    for (size_t i = 0; i < out_plane; ++i) {
      storage->spans.push_back(offset);
      storage->spans.push_back(static_cast<uint32_t>(hi[i] >= 0 ? w.z_lo + lo[i] : 0));
      if (hi[i] >= 0) offset += static_cast<uint32_t>(hi[i] - lo[i] + 1);
    }
    storage->spans.push_back(offset);  // closes the last cell
    storage->spans.push_back(0);
    p.value_count = offset;
    storage->values.resize(p.values_start + offset, 0);
    uint8_t* values = storage->values.data() + p.values_start;
    const uint32_t* spans = storage->spans.data() + p.spans_start;
    for (int32_t z = 0; z < w.nz; ++z) {
      for (int y = 0; y < cells; ++y) {
        const uint8_t* row = w.v.data() + z * plane + static_cast<size_t>(y) * extent;
        for (int x = 0; x < cells; ++x) {
          const size_t i = static_cast<size_t>(y) * cells + x;
          if (z >= lo[i] && z <= hi[i]) values[spans[2 * i] + (z - lo[i])] = row[x];
        }
      }
    }
    placed.push_back(p);
  };
  compress(work, 0);
  for (int k = 1; k <= options.num_layers; ++k) {
    work = nextLayer(work, extent, 1 << (k - 1), options.zShift(k) > options.zShift(k - 1));
    compress(work, options.zShift(k));
  }
  std::vector<RasterLayer> layers;
  for (const Placed& p : placed) {
    RasterLayer L;
    L.z_shift = p.z_shift;
    L.spans = storage->spans.data() + p.spans_start;
    L.values = storage->values.data() + p.values_start;
    L.value_count = static_cast<uint32_t>(p.value_count);
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
