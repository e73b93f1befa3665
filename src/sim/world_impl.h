#pragma once
// Private: the Embree objects behind World, and per-interval snapshots with the actors.

#include <embree3/rtcore.h>

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "gmm_localization/sim/map_aging.h"
#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/snow.h"
#include "gmm_localization/sim/world.h"

namespace gmm_localization {
namespace sim {

struct World::Impl {
  const Town* town = nullptr;
  PassContents pass;
  RTCDevice device = nullptr;
  RTCScene static_scene = nullptr;
  TriangleMesh static_mesh;            // materials and labels per primitive
  std::vector<RTCScene> actor_scenes;  // one per actor
  std::vector<TriangleMesh> actor_meshes;
  std::optional<SnowCover> snow;
  std::function<double(double, double)> cover_depth;  // empty without snow
  MapAging aging;  // empty unless an aged localization pass (repaved stretches shade the road)
  ~Impl();
};

/// The scene for [t0, t1]: the static scene (traced directly) plus a small scene of the actors
/// within `radius_m` of `center`, each instanced with its motion over the interval (ray time
/// 0 = t0, 1 = t1). Rays are traced against both; the nearer hit wins.
class WorldSnapshot {
 public:
  WorldSnapshot(const World& world, double t0, double t1, const Eigen::Vector2d& center,
                double radius_m);
  ~WorldSnapshot();
  WorldSnapshot(const WorldSnapshot&) = delete;
  WorldSnapshot& operator=(const WorldSnapshot&) = delete;

  /// Closest hits of `n` rays (static scene, then actors with the shortened tfar).
  void intersect(RTCIntersectContext* context, RTCRayHit* rays, unsigned n) const;
  double t0() const { return t0_; }
  double t1() const { return t1_; }
  /// Material, label and the world-frame rotation of the hit primitive's normal.
  void surface(const RTCHit& hit, Material* material, uint8_t* label,
               Eigen::Vector3f* normal) const;

 private:
  const World::Impl& world_;
  RTCScene scene_ = nullptr;  // actors only; null when none is near
  double t0_, t1_;
  std::vector<int> instance_actor_;  // actor-scene geomID -> actor index
  std::vector<Eigen::Matrix3f> instance_rotation_;
};

}  // namespace sim
}  // namespace gmm_localization
