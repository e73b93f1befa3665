#include "gmm_localization/core/matching/traversal_image.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gmm_localization {
namespace {

/// A perceptual blue-green-yellow ramp (viridis-like) for u in [0, 1].
void colour(double u, uint8_t* rgb) {
  static const double kStops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  u = std::min(1.0, std::max(0.0, u)) * 4.0;
  const int i = std::min(3, static_cast<int>(u));
  const double f = u - i;
  for (int c = 0; c < 3; ++c) {
    rgb[c] =
        static_cast<uint8_t>(std::lround(kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c])));
  }
}

}  // namespace

TraversalImage renderTraversal(const std::vector<TraversalNode>& nodes, const SearchWindow& window,
                               int top_layer, const SearchOutcome& optimum,
                               const TraversalImageOptions& options) {
  TraversalImage img;
  if (nodes.empty() || top_layer < 0 || window.sizeX() <= 0 || window.sizeY() <= 0) return img;
  const int nh = window.sizeH();
  const int layers = top_layer + 1;
  const int gap = std::max(0, options.gap_px);
  // Tile size: keep the window's aspect, within the per-tile and whole-width budgets.
  const int budget = std::max(
      4, std::min(options.max_tile_px, (options.max_width_px - gap * (nh - 1)) / std::max(1, nh)));
  const double scale =
      std::min(1.0, static_cast<double>(budget) / std::max(window.sizeX(), window.sizeY()));
  img.tile_width = std::max(1, static_cast<int>(std::ceil(window.sizeX() * scale)));
  img.tile_height = std::max(1, static_cast<int>(std::ceil(window.sizeY() * scale)));
  img.width = nh * img.tile_width + (nh - 1) * gap;
  img.height = layers * img.tile_height + (layers - 1) * gap;

  int64_t lo = std::numeric_limits<int64_t>::max(), hi = std::numeric_limits<int64_t>::min();
  for (const TraversalNode& n : nodes) lo = std::min(lo, n.bound), hi = std::max(hi, n.bound);
  const double span = hi > lo ? static_cast<double>(hi - lo) : 1.0;

  // Highest bound per pixel (-1: never scored).
  std::vector<double> best(static_cast<size_t>(img.width) * img.height, -1.0);
  for (const TraversalNode& n : nodes) {
    if (n.layer < 0 || n.layer > top_layer || n.heading_index < 0 || n.heading_index >= nh)
      continue;
    const double u = (n.bound - lo) / span;
    const int row = top_layer - n.layer;  // coarsest on top
    const int x0t = n.heading_index * (img.tile_width + gap);
    const int y0t = row * (img.tile_height + gap);
    const int block = 1 << n.layer;
    const int tx1 = std::min<int>(n.tx + block, window.sizeX());
    const int ty1 = std::min<int>(n.ty + block, window.sizeY());
    const int px0 = static_cast<int>(std::floor(n.tx * scale));
    const int px1 = std::max(px0 + 1, static_cast<int>(std::ceil(tx1 * scale)));
    const int py0 = static_cast<int>(std::floor(n.ty * scale));
    const int py1 = std::max(py0 + 1, static_cast<int>(std::ceil(ty1 * scale)));
    for (int py = py0; py < std::min(py1, img.tile_height); ++py) {
      // y up: translation row 0 at the bottom of the tile.
      const int y = y0t + img.tile_height - 1 - py;
      for (int px = px0; px < std::min(px1, img.tile_width); ++px) {
        double& b = best[static_cast<size_t>(y) * img.width + x0t + px];
        b = std::max(b, u);
      }
    }
  }
  img.rgb.assign(static_cast<size_t>(img.width) * img.height * 3, 0);
  for (size_t i = 0; i < best.size(); ++i) {
    if (best[i] >= 0.0) colour(best[i], &img.rgb[3 * i]);
  }
  // The optimum: a white cross in each tile of its heading.
  if (optimum.heading_index >= 0 && optimum.heading_index < nh) {
    const int cx = optimum.heading_index * (img.tile_width + gap) +
                   std::min(img.tile_width - 1, static_cast<int>(optimum.tx * scale));
    const int arm = std::max(2, img.tile_width / 12);
    for (int row = 0; row < layers; ++row) {
      const int y0t = row * (img.tile_height + gap);
      const int cy = y0t + img.tile_height - 1 -
                     std::min(img.tile_height - 1, static_cast<int>(optimum.ty * scale));
      for (int d = -arm; d <= arm; ++d) {
        for (const auto& [x, y] : {std::pair<int, int>{cx + d, cy}, {cx, cy + d}}) {
          if (x < optimum.heading_index * (img.tile_width + gap) ||
              x >= optimum.heading_index * (img.tile_width + gap) + img.tile_width || y < y0t ||
              y >= y0t + img.tile_height) {
            continue;
          }
          uint8_t* p = &img.rgb[3 * (static_cast<size_t>(y) * img.width + x)];
          p[0] = p[1] = p[2] = 255;
        }
      }
    }
  }
  return img;
}

}  // namespace gmm_localization
