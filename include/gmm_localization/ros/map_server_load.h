#pragma once
// The map server's load_map decision, without ROS (so it is tested without a master): a map is
// switched to only when every one of its tiles reads back (size and CRC-32 against the manifest,
// then decoding). A directory with a truncated or corrupted tile is refused with the tiles and
// the reasons, and the served map stays; loading the same directory again after it was restored
// starts over with every tile read afresh (a new map version).

#include <cstddef>
#include <string>

#include "gmm_localization/core/raster/chunk_engine.h"

namespace gmm_localization {
namespace node {

struct LoadMapOutcome {
  bool success = false;
  std::string message;  ///< what is served now, or why the map was kept
};

/// Checks `directory` and switches `engine` to it; on failure names at most max_listed bad
/// tiles (with their reasons) and how many more there are.
LoadMapOutcome loadMapDirectory(ChunkEngine& engine, const std::string& directory,
                                size_t max_listed = 5);

}  // namespace node
}  // namespace gmm_localization
