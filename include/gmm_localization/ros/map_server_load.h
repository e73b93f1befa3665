#pragma once
// The map server's load_map decision, without ROS (so it is tested without a master): a map is
// switched to only when every one of its tiles reads back (size and CRC-32 against the manifest,
// then decoding). A directory with a truncated or corrupted tile is refused with the tiles and
// the reasons, and the served map stays; loading the same directory again after it was restored
// starts over with every tile read afresh (a new map version).

#include <cstddef>
#include <string>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/raster/chunk_engine.h"

namespace gmm_localization {
namespace node {

struct LoadMapOutcome {
  bool success = false;
  std::string message;  ///< what is served now, or why the map was kept
};

/// Empty when `store` holds the `wanted` layer, else why not and how to get it (the build_map
/// option, the launch argument): a map server asked for the reflectivity layer of a map that
/// has only its height layer must say so at start-up, not serve heights to a reflectivity
/// matcher.
std::string layerProblem(const MapStore& store, MapLayer wanted);
/// What to add to a failure to open `directory` as the `wanted` layer (empty for height).
std::string layerHint(const std::string& directory, MapLayer wanted);

/// Checks `directory` (its tiles, and that it holds the `wanted` layer) and switches `engine`
/// to it; on failure names at most max_listed bad tiles (with their reasons) and how many more
/// there are.
LoadMapOutcome loadMapDirectory(ChunkEngine& engine, const std::string& directory,
                                size_t max_listed = 5, MapLayer wanted = MapLayer::kHeight);

}  // namespace node
}  // namespace gmm_localization
