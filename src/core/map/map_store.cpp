#include "gmm_localization/core/map/map_store.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>

namespace gmm_localization {

uint64_t MapSummary::cells() const {
  uint64_t n = 0;
  for (uint64_t c : cells_by_components) n += c;
  return n;
}

Result<MapStore> MapStore::open(const std::string& directory) {
  auto manifest = readManifest(directory);
  if (!manifest) return Result<MapStore>::failure(manifest.error());
  MapStore store;
  store.directory_ = directory;
  store.manifest_ = std::move(*manifest);
  for (size_t i = 0; i < store.manifest_.tiles.size(); ++i) {
    store.index_[store.manifest_.tiles[i].id] = i;
  }
  struct stat st;
  const std::string path = directory + "/" + kManifestFileName;
  if (::stat(path.c_str(), &st) == 0) store.manifest_bytes_ = static_cast<uint64_t>(st.st_size);
  return store;
}

std::vector<TileId> MapStore::tileIds() const {
  std::vector<TileId> ids;
  ids.reserve(index_.size());
  for (const auto& entry : index_) ids.push_back(entry.first);
  return ids;
}

const TileInfo* MapStore::tileInfo(const TileId& id) const {
  auto it = index_.find(id);
  return it == index_.end() ? nullptr : &manifest_.tiles[it->second];
}

Result<GmmTileConstPtr> MapStore::loadTile(const TileId& id) const {
  const TileInfo* info = tileInfo(id);
  if (!info) {
    return Result<GmmTileConstPtr>::failure("no tile (" + std::to_string(id.x) + ", " +
                                            std::to_string(id.y) + ") in map '" + directory_ + "'");
  }
  auto tile = readTileFile(directory_, *info, manifest_.geometry);
  if (!tile) return Result<GmmTileConstPtr>::failure(tile.error());
  return GmmTileConstPtr(std::move(*tile));
}

std::vector<TileId> MapStore::tilesWithin(double x_m, double y_m, double radius_m) const {
  std::vector<TileId> out;
  if (!(radius_m >= 0.0) || !std::isfinite(x_m) || !std::isfinite(y_m)) return out;
  const MapGeometry& g = manifest_.geometry;
  const double size_m = g.tileSizeM();
  for (const auto& entry : index_) {
    const TileId& t = entry.first;
    const double x0 = g.origin_x_m + t.x * size_m, y0 = g.origin_y_m + t.y * size_m;
    const double dx = std::max({x0 - x_m, 0.0, x_m - (x0 + size_m)});
    const double dy = std::max({y0 - y_m, 0.0, y_m - (y0 + size_m)});
    if (dx * dx + dy * dy <= radius_m * radius_m) out.push_back(t);
  }
  return out;
}

Result<std::vector<GmmTileConstPtr>> MapStore::loadTilesWithin(double x_m, double y_m,
                                                               double radius_m) const {
  std::vector<GmmTileConstPtr> tiles;
  for (const TileId& id : tilesWithin(x_m, y_m, radius_m)) {
    auto tile = loadTile(id);
    if (!tile) return Result<std::vector<GmmTileConstPtr>>::failure(tile.error());
    tiles.push_back(std::move(*tile));
  }
  return tiles;
}

Result<GmmMap> MapStore::loadAll() const {
  GmmMap map(manifest_.geometry);
  for (const auto& entry : index_) {
    auto tile = loadTile(entry.first);
    if (!tile) return Result<GmmMap>::failure(tile.error());
    map.insert(std::move(*tile));
  }
  return map;
}

MapSummary MapStore::summary() const {
  MapSummary s;
  s.tiles = manifest_.tiles.size();
  s.manifest_bytes = manifest_bytes_;
  const MapGeometry& g = manifest_.geometry;
  bool first = true, any_z = false;
  for (const TileInfo& t : manifest_.tiles) {
    for (int k = 0; k <= kMaxMixtureComponents; ++k)
      s.cells_by_components[k] += t.cells_by_components[k];
    s.tile_bytes += t.byte_size;
    const double x0 = g.origin_x_m + t.id.x * g.tileSizeM(),
                 y0 = g.origin_y_m + t.id.y * g.tileSizeM();
    s.min_x_m = first ? x0 : std::min(s.min_x_m, x0);
    s.min_y_m = first ? y0 : std::min(s.min_y_m, y0);
    s.max_x_m = first ? x0 + g.tileSizeM() : std::max(s.max_x_m, x0 + g.tileSizeM());
    s.max_y_m = first ? y0 + g.tileSizeM() : std::max(s.max_y_m, y0 + g.tileSizeM());
    first = false;
    const bool has_components =
        t.cells_by_components[0] < static_cast<uint64_t>(g.tile_size_cells) * g.tile_size_cells;
    if (has_components) {
      s.z_min_m = any_z ? std::min(s.z_min_m, t.z_min_m) : t.z_min_m;
      s.z_max_m = any_z ? std::max(s.z_max_m, t.z_max_m) : t.z_max_m;
      any_z = true;
    }
  }
  return s;
}

std::vector<std::string> MapStore::verify() const {
  std::vector<std::string> errors;
  for (const auto& entry : index_) {
    auto tile = loadTile(entry.first);
    if (!tile) errors.push_back(tile.error());
  }
  return errors;
}

}  // namespace gmm_localization
