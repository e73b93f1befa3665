#include "town_blocks.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {
namespace sim {
namespace {

struct Interval {
  double lo, hi;
  bool road_lo, road_hi;
};

std::vector<Interval> intervals(const std::vector<double>& lines, double half, double margin) {
  std::vector<Interval> out;
  out.push_back({lines.front() - half - margin, lines.front() - half, false, true});
  for (size_t k = 0; k + 1 < lines.size(); ++k)
    out.push_back({lines[k] + half, lines[k + 1] - half, true, true});
  out.push_back({lines.back() + half, lines.back() + half + margin, true, false});
  return out;
}

}  // namespace

std::vector<Block> townBlocks(const Town& town) {
  const double half = 0.5 * town.config().road_width_m;
  const double margin = town.config().outer_margin_m;
  std::vector<Block> blocks;
  for (const Interval& iy : intervals(town.roadY(), half, margin)) {
    for (const Interval& ix : intervals(town.roadX(), half, margin)) {
      blocks.push_back(
          {ix.lo, ix.hi, iy.lo, iy.hi, {ix.road_lo, ix.road_hi, iy.road_lo, iy.road_hi}});
    }
  }
  return blocks;
}

int meshCells(double length_m, double step_m) {
  return std::max(1, static_cast<int>(std::ceil(length_m / step_m - 1e-9)));
}

}  // namespace sim
}  // namespace gmm_localization
