#pragma once
// The synthetic street of support/synthetic_world.h as the registration and pipeline tests
// search it: 20 cm cells in 128-cell tiles, rasterized with the default options over chunks
// -4..3 in x and y (the street and its surroundings).

#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/synthetic_world.h"

namespace gmm_localization {
namespace testing {

inline MapGeometry streetGeometry() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 128;
  return g;
}

/// The rasterized chunks of `gmm` (built by SyntheticWorld::buildMap on streetGeometry()).
inline ChunkMap rasterizeStreet(const GmmMap& gmm) {
  const RasterOptions o;
  ChunkMap chunks(streetGeometry(), o);
  for (int cy = -4; cy <= 3; ++cy) {
    for (int cx = -4; cx <= 3; ++cx) chunks.insert(rasterizeChunk(gmm, {cx, cy}, o).value());
  }
  return chunks;
}

}  // namespace testing
}  // namespace gmm_localization
