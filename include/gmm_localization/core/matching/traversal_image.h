#pragma once
// A picture of one branch-and-bound traversal, like the paper's Fig. 9: a grid of tiles with
// one row per layer (coarsest on top, base layer at the bottom) and one column per heading.
// Each tile shows the window's translations (x to the right, y up); every scored node paints
// its 2^k x 2^k block of translations with its bound on a colour scale (dark blue = lowest
// bound scored, yellow = highest); never-scored translations stay black; the optimum is marked
// with a white cross in every tile of its heading. Tiles larger than the pixel budget are
// downsampled keeping, per pixel, the highest bound. ROS-free (the matcher publishes it as a
// sensor_msgs/Image, `evaluate` writes it as a PNG).

#include <cstdint>
#include <vector>

#include "gmm_localization/core/matching/grid_search.h"

namespace gmm_localization {

struct TraversalImageOptions {
  int max_width_px = 2048;  ///< whole image width budget [pixels]
  int max_tile_px = 160;    ///< largest tile edge [pixels]
  int gap_px = 2;           ///< gap between tiles [pixels]
};

struct TraversalImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  ///< row-major, 3 bytes per pixel, top row first
  int tile_width = 0;        ///< pixels per tile
  int tile_height = 0;
};

/// Renders `nodes` (from branchAndBoundSearch) for a window of `window`'s sizes searched down
/// from `top_layer`, with the optimum (heading_index, tx, ty). Empty image when there is
/// nothing to draw.
TraversalImage renderTraversal(const std::vector<TraversalNode>& nodes, const SearchWindow& window,
                               int top_layer, const SearchOutcome& optimum,
                               const TraversalImageOptions& options = {});

}  // namespace gmm_localization
