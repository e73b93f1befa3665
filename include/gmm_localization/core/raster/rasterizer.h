#pragma once
// Online rasterization of the parametric Gaussian mixture map into multiresolution lookup
// tables (paper IV-B): "rasterized multiresolution maps computed online from the parametrized
// map as a background job, incrementally using each layer to build the next".

#include <cstdint>
#include <utility>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/gaussian_mixture.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

/// Local maxima of a mixture's density (at most one per component in practice), found by a
/// scan at a quarter of the smallest sigma between the extreme means, each refined by
/// golden-section search. Empty for an empty mixture.
std::vector<double> mixtureModes(const GaussianMixture1D& g);

/// Heights [m] outside which log p(z) < ll_floor for sure: for each component j the interval
/// where log(w_j N_j(z)) >= ll_floor - log K, joined. Returns {+inf, -inf} when nowhere above.
std::pair<double, double> aboveFloorRange(const GaussianMixture1D& g, double ll_floor);

/// Base-layer values of one cell for z bins [zb_lo, zb_lo + nz): out[i * stride] =
/// q(max over the bin of log p(z)), exact up to the mode search above; 0 where below the floor.
void rasterizeCell(const GaussianMixture1D& g, int32_t zb_lo, int32_t nz, double z_step_m,
                   const ScoreQuantizer& quantizer, uint8_t* out, size_t stride);

/// Rasterizes chunk `id` of `map` (cells of 2^options.chunk_shift): the base layer, then layers
/// 1..num_layers each from the previous one. Layer k at a cell reads base cells up to 2^k - 1
/// beyond the chunk's +x/+y edges: it reads exactly the cells chunkReadCells() names
/// (chunk_reach.h), so the tiles chunkReadTiles() names must be in `map` when they exist (absent
/// tiles count as empty: then the bound is exact for the map as given). Pure; safe to run on a
/// background thread while `map` is not modified. Fails only on invalid options.
Result<MapChunkConstPtr> rasterizeChunk(const GmmMap& map, ChunkId id,
                                        const RasterOptions& options);

}  // namespace gmm_localization
