// The load_map decision of the map server (map_server_load.h).
#include "gmm_localization/ros/map_server_load.h"

#include <vector>

#include "gmm_localization/core/map/map_store.h"

namespace gmm_localization {
namespace node {
namespace {

/// Empty when every tile of the map in `directory` loads, else which ones do not and why.
std::string badTiles(const MapStore& store, size_t max_listed) {
  std::vector<std::string> bad;
  const std::vector<TileId> ids = store.tileIds();
  for (const TileId& id : ids) {
    auto tile = store.loadTile(id);
    if (!tile) {
      bad.push_back("tile (" + std::to_string(id.x) + ", " + std::to_string(id.y) +
                    "): " + tile.error());
    }
  }
  if (bad.empty()) return {};
  std::string out =
      std::to_string(bad.size()) + " of " + std::to_string(ids.size()) + " tile(s) do not load: ";
  for (size_t i = 0; i < bad.size() && i < max_listed; ++i) out += (i ? "; " : "") + bad[i];
  if (bad.size() > max_listed) {
    out += "; and " + std::to_string(bad.size() - max_listed) + " more";
  }
  return out;
}

}  // namespace

std::string layerProblem(const MapStore& store, MapLayer wanted) {
  if (store.layer() == wanted) return {};
  const std::string d = store.directory();
  if (wanted == MapLayer::kReflectivity) {
    return "map '" + d +
           "' holds the height layer, not the reflectivity layer: build it from the same inputs "
           "with build_map --layer reflectivity --output MAP/reflectivity (localization.launch "
           "method:=reflectivity serves MAP/reflectivity)";
  }
  return "map '" + d +
         "' holds the reflectivity layer, not the height layer: serve it with layer: "
         "reflectivity and the matcher's method: reflectivity (localization.launch "
         "method:=reflectivity map:=MAP, not map:=MAP/reflectivity)";
}

std::string layerHint(const std::string& directory, MapLayer wanted) {
  if (wanted != MapLayer::kReflectivity) return {};
  return " (the reflectivity layer was asked for in '" + directory +
         "': build it with build_map --layer reflectivity --output " + directory +
         " from the inputs of the height map)";
}

LoadMapOutcome loadMapDirectory(ChunkEngine& engine, const std::string& directory,
                                size_t max_listed, MapLayer wanted) {
  LoadMapOutcome out;
  const std::string kept = "kept map '" + engine.store()->directory() + "': ";
  // Every tile is read once here (the 3 km Downtown map is 5 MB): a map with broken tiles
  // would otherwise be served with holes that the caller was told were not there.
  auto store = MapStore::open(directory);
  if (!store) {
    out.message = kept + store.error() + layerHint(directory, wanted);
    return out;
  }
  const std::string layer = layerProblem(*store, wanted);
  if (!layer.empty()) {
    out.message = kept + layer;
    return out;
  }
  const std::string bad = badTiles(*store, max_listed);
  if (!bad.empty()) {
    out.message = kept + "map '" + directory + "' refused: " + bad;
    return out;
  }
  const Status s = engine.switchMap(directory);
  if (!s.ok()) {
    out.message = kept + s.error();
    return out;
  }
  const MapSummary m = engine.mapSummary();
  out.success = true;
  out.message = "serving map '" + directory + "' (" + std::to_string(m.tiles) +
                " tiles), map_version " + std::to_string(engine.mapVersion());
  return out;
}

}  // namespace node
}  // namespace gmm_localization
