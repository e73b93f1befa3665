#include "gmm_localization/core/raster/chunk_reach.h"

namespace gmm_localization {

int64_t chunkReachCells(const RasterOptions& options) {
  return (int64_t{1} << options.num_layers) - 1;
}

CellRect chunkReadCells(ChunkId id, const RasterOptions& options) {
  const int64_t cells = options.chunkCells();
  const int64_t extent = cells + chunkReachCells(options);
  CellRect r;
  r.lo = {static_cast<int64_t>(id.x) * cells, static_cast<int64_t>(id.y) * cells};
  r.hi = {r.lo.x + extent - 1, r.lo.y + extent - 1};
  return r;
}

std::vector<TileId> tilesCovering(const MapGeometry& geometry, const CellRect& cells) {
  std::vector<TileId> out;
  if (cells.hi.x < cells.lo.x || cells.hi.y < cells.lo.y) return out;
  const TileId lo = geometry.tileOf(cells.lo);
  const TileId hi = geometry.tileOf(cells.hi);
  for (int32_t tx = lo.x; tx <= hi.x; ++tx) {
    for (int32_t ty = lo.y; ty <= hi.y; ++ty) out.push_back({tx, ty});
  }
  return out;
}

std::vector<TileId> chunkReadTiles(const MapGeometry& geometry, ChunkId id,
                                   const RasterOptions& options) {
  return tilesCovering(geometry, chunkReadCells(id, options));
}

}  // namespace gmm_localization
