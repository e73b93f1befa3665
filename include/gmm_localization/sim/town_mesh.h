#pragma once
// Meshing of the town's ground: crowned road surfaces, curb faces, sidewalks and lots, with an
// optional cover (snow) that raises the surfaces by a smooth depth.

#include <functional>

#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

struct GroundCover {
  /// Extra height above the bare ground at (x, y) [m] (>= 0); empty = no cover.
  std::function<double(double, double)> depth_m;
  /// Material of covered surfaces (snow hides asphalt, concrete and paint).
  Material material = Material::kSnow;
};

/// Ground mesh (label kLabelStatic). Vertices on shared borders coincide, so no ray leaks.
TriangleMesh buildGroundMesh(const Town& town, const GroundCover& cover = {});

}  // namespace sim
}  // namespace gmm_localization
