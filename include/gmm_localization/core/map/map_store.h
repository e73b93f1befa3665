#pragma once
// Read access to a Gaussian mixture map on disk (a directory written by MapBuilder): the
// manifest, the tile list, and tile loading by id or around a point.
//
// Thread safety: all methods are const and keep no mutable state, so one MapStore may serve
// several threads (e.g. a background rasterizer). Tiles are decoded on every load; caching is
// the caller's choice (the map server keeps the tiles near the vehicle).
//
// Failure behaviour: open() and every load return a failure whose reason names the file and
// the problem (see map_format.h). Nothing is ever partly loaded.

#include <array>
#include <map>
#include <string>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {

/// Map-wide statistics, from the manifest alone (no tile is read).
struct MapSummary {
  size_t tiles = 0;
  /// cells_by_components[k]: cells with exactly k components, over all tiles present.
  std::array<uint64_t, kMaxMixtureComponents + 1> cells_by_components{};
  uint64_t tile_bytes = 0;      ///< sum of the tile file sizes [bytes]
  uint64_t manifest_bytes = 0;  ///< size of manifest.gmm [bytes]
  /// Map-frame bounding box of the tiles present [m] (all 0 for a map without tiles).
  double min_x_m = 0.0, min_y_m = 0.0, max_x_m = 0.0, max_y_m = 0.0;
  /// Union of the tiles' z ranges [m] (mean -/+ 4 sigma); 0, 0 when there is no component.
  float z_min_m = 0.f, z_max_m = 0.f;

  uint64_t bytesOnDisk() const { return tile_bytes + manifest_bytes; }
  uint64_t cells() const;
  uint64_t nonEmptyCells() const { return cells() - cells_by_components[0]; }
};

class MapStore {
 public:
  /// Opens the map in `directory` by reading and checking its manifest (tiles are not read).
  static Result<MapStore> open(const std::string& directory);

  const std::string& directory() const { return directory_; }
  const MapManifest& manifest() const { return manifest_; }
  const MapGeometry& geometry() const { return manifest_.geometry; }
  /// What the cells hold (map_format.h, reflectivity_layer.h): kHeight for maps before format
  /// version 3.
  MapLayer layer() const { return manifest_.layer; }
  /// The reflectivity layer's definition the map was built with (meaningful for
  /// layer() == kReflectivity only).
  const ReflectivityLayerOptions& reflectivity() const { return manifest_.reflectivity; }

  /// Ids of the tiles the map holds, ascending (x, then y).
  std::vector<TileId> tileIds() const;
  /// The manifest entry of a tile, or nullptr when the map has no such tile (no data there).
  const TileInfo* tileInfo(const TileId& id) const;
  bool hasTile(const TileId& id) const { return tileInfo(id) != nullptr; }

  /// Reads, checks (size, CRC, header) and decodes one tile. Fails for a tile the map does not
  /// hold ("no tile (x, y) in map ...") and for any file problem.
  Result<GmmTileConstPtr> loadTile(const TileId& id) const;

  /// Tiles the map holds whose square comes within radius_m of map-frame point (x_m, y_m),
  /// ascending. radius_m < 0 gives none.
  std::vector<TileId> tilesWithin(double x_m, double y_m, double radius_m) const;
  /// Loads tilesWithin(); fails on the first tile that cannot be loaded (use tilesWithin and
  /// loadTile to skip bad tiles instead).
  Result<std::vector<GmmTileConstPtr>> loadTilesWithin(double x_m, double y_m,
                                                       double radius_m) const;
  /// Loads every tile into an in-memory map.
  Result<GmmMap> loadAll() const;

  MapSummary summary() const;

  /// Loads every tile and returns one message per tile that fails (empty when all are sound).
  std::vector<std::string> verify() const;

 private:
  MapStore() = default;
  std::string directory_;
  MapManifest manifest_;
  uint64_t manifest_bytes_ = 0;
  std::map<TileId, size_t> index_;  // tile id -> position in manifest_.tiles
};

}  // namespace gmm_localization
