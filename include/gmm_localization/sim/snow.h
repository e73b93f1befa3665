#pragma once
// Snow of the snowy pass: cover depth over the ground, and snowbanks along the curbs.

#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/pass.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

/// Smooth snow depth [m] in [snow_depth_min_m, snow_depth_max_m].
class SnowCover {
 public:
  explicit SnowCover(const PassConfig& config);
  double depth(double x, double y) const;

 private:
  double min_, max_;
  double phase_[6];
};

/// Snowbank meshes (label kLabelSnow) along every curb facing a road, with gaps.
TriangleMesh buildSnowbanks(const Town& town, const PassConfig& config, const SnowCover& cover);

}  // namespace sim
}  // namespace gmm_localization
