#pragma once
// World: the town plus one pass (parked cars, actors, snow, map aging) as an Embree 3 scene
// ready for ray casting. Static triangles (ground, objects, parked cars, aging objects,
// snowbanks) form one instanced scene;
// each actor is its own small scene, instanced with a two-step motion-blur transform per
// revolution so that moving objects smear as they do in a real spinning LIDAR. The Town must
// outlive the World. Embree objects stay behind the pimpl (src/sim/world_impl.h).

#include <memory>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/pass.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

class World {
 public:
  struct Impl;
  /// Builds the BVHs with `threads` Embree worker threads. `extra` (optional) adds triangles to
  /// the static scene (tests place walls with it). Fails with Embree's error text.
  static Result<std::shared_ptr<World>> create(const Town& town, const PassConfig& pass,
                                               int threads = 2,
                                               const TriangleMesh* extra = nullptr);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const Town& town() const;
  /// The pass contents; with map aging, without the parked cars the aging objects displaced.
  const PassContents& pass() const;
  /// What map aging changed (empty for the mapping pass and for aging mode none).
  const MapAging& aging() const;
  size_t numStaticTriangles() const;
  /// Ground height including the pass's snow cover [m].
  double surfaceHeight(double x, double y) const;
  const Impl& impl() const { return *impl_; }

 private:
  World();
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim
}  // namespace gmm_localization
