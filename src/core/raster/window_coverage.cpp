#include "gmm_localization/core/raster/window_coverage.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace gmm_localization {

WindowCoverage windowCoverage(const ChunkMap& map, double cx, double cy, double half_x_m,
                              double half_y_m) {
  WindowCoverage c;
  c.loaded_chunks = map.size();
  const MapGeometry& g = map.geometry();
  c.centre_loaded = map.find(map.chunkOf(g.cellAt(cx, cy))) != nullptr;
  const double area = 4.0 * half_x_m * half_y_m;
  if (!(area > 0.0) || !std::isfinite(area)) return c;
  const double x0 = cx - half_x_m, x1 = cx + half_x_m, y0 = cy - half_y_m, y1 = cy + half_y_m;
  double covered = 0.0;
  for (const auto& kv : map.chunks()) {
    const MapChunk& chunk = *kv.second;
    const CellIndex o = chunk.origin();
    const double size_m = chunk.cells() * g.resolution_m;
    const double cx0 = g.origin_x_m + static_cast<double>(o.x) * g.resolution_m;
    const double cy0 = g.origin_y_m + static_cast<double>(o.y) * g.resolution_m;
    const double w = std::min(x1, cx0 + size_m) - std::max(x0, cx0);
    const double h = std::min(y1, cy0 + size_m) - std::max(y0, cy0);
    if (w > 0.0 && h > 0.0) covered += w * h;
  }
  c.loaded_share = std::min(1.0, covered / area);
  return c;
}

std::string describeWindowCoverage(const WindowCoverage& c, double cx, double cy, double half_x_m) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(0) << 100.0 * c.loaded_share << "% of the +-" << half_x_m
    << " m window around (" << std::setprecision(1) << cx << ", " << cy
    << ") is over the loaded map (" << c.loaded_chunks << " chunks)";
  return s.str();
}

}  // namespace gmm_localization
