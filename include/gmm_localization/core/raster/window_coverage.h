#pragma once
// How much of a search window the loaded raster chunks cover. The map server holds the chunks
// near the vehicle only, so a global search asked for around an estimate outside them, or over a
// window larger than what it holds, would search cells that read as the floor: the matcher
// refuses the first (its global_localization service) and says how much of the window was
// loaded for the second (the service's answer, a rejected global match's reason).
//
// Units: map frame [m]; the window is the square [cx - half_x, cx + half_x] x
// [cy - half_y, cy + half_y].

#include <cstddef>
#include <string>

#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

struct WindowCoverage {
  bool centre_loaded = false;  ///< the chunk under the window's centre is loaded
  double loaded_share = 0.0;   ///< share of the window's area over loaded chunks, in [0, 1]
  size_t loaded_chunks = 0;    ///< chunks in the map
};

/// The coverage of the window by `map`'s chunks (exact: the sum of the chunk squares'
/// intersections with the window, chunks being disjoint). A window of zero area has share 0.
WindowCoverage windowCoverage(const ChunkMap& map, double centre_x_m, double centre_y_m,
                              double half_x_m, double half_y_m);

/// "73% of the +-50 m window around (x, y) is over the loaded map (412 chunks)", for messages.
std::string describeWindowCoverage(const WindowCoverage& coverage, double centre_x_m,
                                   double centre_y_m, double half_x_m);

}  // namespace gmm_localization
