#pragma once
// The read rule of a raster chunk: which map cells rasterizeChunk (rasterizer.h) reads for a
// chunk, and which tiles cover them. Everything that loads tiles for a chunk (the map server's
// planner, rasterizeRegion) uses this rule, and the rasterizer reads exactly the cells it names.
//
// Why the chunk reaches past its own cells: layer k at a cell is the max over the 2^k x 2^k
// block of base cells starting there (towards +x and +y, map_chunk.h), so the coarsest layer of
// the chunk's last cell reads R = 2^num_layers - 1 cells beyond the chunk's +x/+y edges. The
// branch-and-bound's bounds are admissible only when those cells' mixtures are present wherever
// the map has them: a chunk rasterized from a map holding every tile chunkReadTiles() names
// equals the chunk rasterized from the whole map (test/unit/raster/chunk_reach_test.cpp).
//
// Units: cell and tile indices of the map grid (core/map/map_geometry.h); indices may be
// negative.

#include <cstdint>
#include <vector>

#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

/// A rectangle of cells, both corners inclusive: lo.x <= x <= hi.x, lo.y <= y <= hi.y.
struct CellRect {
  CellIndex lo;
  CellIndex hi;

  int64_t widthCells() const { return hi.x - lo.x + 1; }
  int64_t heightCells() const { return hi.y - lo.y + 1; }
  bool contains(const CellIndex& c) const {
    return c.x >= lo.x && c.x <= hi.x && c.y >= lo.y && c.y <= hi.y;
  }
};

/// R = 2^num_layers - 1: the cells past a chunk's +x/+y edges that its layers read.
int64_t chunkReachCells(const RasterOptions& options);

/// The cells the rasterization of chunk `id` reads: [origin, origin + C + R) per axis, with
/// C = options.chunkCells() and origin = MapChunk::origin().
CellRect chunkReadCells(ChunkId id, const RasterOptions& options);

/// Every tile that overlaps `cells` (whether or not a map holds it), ascending (x, then y).
std::vector<TileId> tilesCovering(const MapGeometry& geometry, const CellRect& cells);

/// tilesCovering(geometry, chunkReadCells(id, options)).
std::vector<TileId> chunkReadTiles(const MapGeometry& geometry, ChunkId id,
                                   const RasterOptions& options);

}  // namespace gmm_localization
