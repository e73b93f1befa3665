#include "world_impl.h"

namespace gmm_localization {
namespace sim {
namespace {

void toColumnMajor3x4(const Eigen::Isometry3d& t, float out[12]) {
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) out[c * 3 + r] = static_cast<float>(t.linear()(r, c));
  for (int r = 0; r < 3; ++r) out[9 + r] = static_cast<float>(t.translation()(r));
}

}  // namespace

WorldSnapshot::WorldSnapshot(const World& world, double t0, double t1,
                             const Eigen::Vector2d& center, double radius_m)
    : world_(world.impl()), t0_(t0), t1_(t1) {
  const World::Impl& w = world_;
  float xfm[12];
  for (size_t k = 0; k < w.pass.actors.size(); ++k) {
    const Actor& a = w.pass.actors[k];
    if (!a.continuousOver(t0, t1)) continue;
    Eigen::Isometry3d p0, p1;
    a.poseAt(*w.town, t0, &p0);
    if ((p0.translation().head<2>() - center).norm() > radius_m) continue;
    a.poseAt(*w.town, t1, &p1);
    if (scene_ == nullptr) {
      scene_ = rtcNewScene(w.device);
      rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
    }
    RTCGeometry g = rtcNewGeometry(w.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, w.actor_scenes[k]);
    rtcSetGeometryTimeStepCount(g, 2);
    toColumnMajor3x4(p0, xfm);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    toColumnMajor3x4(p1, xfm);
    rtcSetGeometryTransform(g, 1, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    if (id >= instance_actor_.size()) {
      instance_actor_.resize(id + 1, -1);
      instance_rotation_.resize(id + 1, Eigen::Matrix3f::Identity());
    }
    instance_actor_[id] = static_cast<int>(k);
    instance_rotation_[id] = p0.linear().cast<float>();
  }
  if (scene_ != nullptr) rtcCommitScene(scene_);
}

void WorldSnapshot::intersect(RTCIntersectContext* context, RTCRayHit* rays, unsigned n) const {
  rtcIntersect1M(world_.static_scene, context, rays, n, sizeof(RTCRayHit));
  if (scene_ != nullptr) rtcIntersect1M(scene_, context, rays, n, sizeof(RTCRayHit));
}

WorldSnapshot::~WorldSnapshot() {
  if (scene_) rtcReleaseScene(scene_);
}

void WorldSnapshot::surface(const RTCHit& hit, Material* material, uint8_t* label,
                            Eigen::Vector3f* normal) const {
  const unsigned inst = hit.instID[0];
  const Eigen::Vector3f ng(hit.Ng_x, hit.Ng_y, hit.Ng_z);
  if (inst == RTC_INVALID_GEOMETRY_ID || inst >= instance_actor_.size()) {  // static scene
    *material = world_.static_mesh.materials[hit.primID];
    *label = world_.static_mesh.labels[hit.primID];
    *normal = ng;
    return;
  }
  const TriangleMesh& mesh = world_.actor_meshes[instance_actor_[inst]];
  *material = mesh.materials[hit.primID];
  *label = mesh.labels[hit.primID];
  *normal = instance_rotation_[inst] * ng;
}

}  // namespace sim
}  // namespace gmm_localization
