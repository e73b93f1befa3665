#pragma once
// Private helpers shared by the town's layout and ground meshing: the blocks between roads.

#include <vector>

#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

/// An axis-aligned block between curb lines; faces[k] tells whether side k faces a road
/// (k: 0 west, 1 east, 2 south, 3 north).
struct Block {
  double x0, x1, y0, y1;
  bool faces[4];
};

std::vector<Block> townBlocks(const Town& town);

/// Number of mesh cells along a length with the configured step (at least 1).
int meshCells(double length_m, double step_m);

}  // namespace sim
}  // namespace gmm_localization
