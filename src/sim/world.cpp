#include "gmm_localization/sim/world.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "gmm_localization/sim/town_mesh.h"
#include "world_impl.h"

namespace gmm_localization {
namespace sim {
namespace {

std::string embreeError(RTCDevice device, const char* what) {
  return std::string("embree: ") + what + " failed (error code " +
         std::to_string(rtcGetDeviceError(device)) + ")";
}

RTCScene meshScene(RTCDevice device, const TriangleMesh& mesh, RTCBuildQuality quality) {
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, quality);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, quality);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.numVertices()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.numTriangles()));
  if (vb == nullptr || ib == nullptr) {
    rtcReleaseGeometry(geom);
    rtcReleaseScene(scene);
    return nullptr;
  }
  std::memcpy(vb, mesh.vertices.data(), mesh.vertices.size() * sizeof(float));
  std::memcpy(ib, mesh.indices.data(), mesh.indices.size() * sizeof(unsigned));
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  return scene;
}

}  // namespace

World::Impl::~Impl() {
  for (RTCScene s : actor_scenes) rtcReleaseScene(s);
  if (static_scene) rtcReleaseScene(static_scene);
  if (device) rtcReleaseDevice(device);
}

World::World() : impl_(std::make_unique<Impl>()) {}
World::~World() = default;
const Town& World::town() const { return *impl_->town; }
const PassContents& World::pass() const { return impl_->pass; }
const MapAging& World::aging() const { return impl_->aging; }
size_t World::numStaticTriangles() const { return impl_->static_mesh.numTriangles(); }

double World::surfaceHeight(double x, double y) const {
  const double g = impl_->town->groundHeight(x, y);
  return impl_->cover_depth ? g + impl_->cover_depth(x, y) : g;
}

Result<std::shared_ptr<World>> World::create(const Town& town, const PassConfig& pass_config,
                                             int threads, const TriangleMesh* extra) {
  using R = Result<std::shared_ptr<World>>;
  const Status valid = pass_config.validate();
  if (!valid) return R::failure(valid.error());
  std::shared_ptr<World> world(new World());
  Impl& w = *world->impl_;
  w.town = &town;
  w.pass = preparePass(town, pass_config);
  if (pass_config.type != PassType::kMapping) {
    // The town a few months after the mapping drive; parked cars cannot stand in a fenced
    // site or under a container.
    w.aging = planMapAging(town, pass_config.aging);
    auto& cars = w.pass.parked;
    const size_t before = cars.size();
    cars.erase(std::remove_if(cars.begin(), cars.end(),
                              [&](const ParkedCar& c) {
                                Footprint f;
                                f.center = c.center;
                                f.yaw_rad = c.yaw_rad;
                                f.half_length_m = 0.5 * c.shape.length_m;
                                f.half_width_m = 0.5 * c.shape.width_m;
                                return w.aging.blocks(f);
                              }),
               cars.end());
    w.aging.removed_parked_cars = before - cars.size();
  }
  const std::string cfg = "threads=" + std::to_string(std::max(1, threads));
  w.device = rtcNewDevice(cfg.c_str());
  if (w.device == nullptr) return R::failure("embree: rtcNewDevice(\"" + cfg + "\") failed");

  GroundCover cover;
  if (pass_config.snow) {
    w.snow.emplace(pass_config);
    const SnowCover* snow = &*w.snow;
    const Town* t = &town;
    const double crown = town.config().crown_height_m;
    // Snow fills the gutters: half of the crown is levelled on roads.
    w.cover_depth = [snow, t, crown](double x, double y) {
      double d = snow->depth(x, y);
      if (t->onRoad(x, y)) d += 0.5 * (crown - (t->groundHeight(x, y) - t->terrainHeight(x, y)));
      return d;
    };
    cover.depth_m = w.cover_depth;
  }
  w.static_mesh = buildGroundMesh(town, cover);
  w.static_mesh.append(town.objects());
  for (const ParkedCar& car : w.pass.parked) {
    const Eigen::Vector3d g(car.center.x(), car.center.y(),
                            world->surfaceHeight(car.center.x(), car.center.y()));
    addCar(w.static_mesh, g, car.yaw_rad, car.shape, car.label);
  }
  if (!w.aging.empty()) {
    const World* self = world.get();
    addMapAgingMesh(
        town, w.aging, [self](double x, double y) { return self->surfaceHeight(x, y); },
        &w.static_mesh);
  }
  if (w.snow) w.static_mesh.append(buildSnowbanks(town, pass_config, *w.snow));
  if (extra) w.static_mesh.append(*extra);
  w.static_scene = meshScene(w.device, w.static_mesh, RTC_BUILD_QUALITY_HIGH);
  if (w.static_scene == nullptr) return R::failure(embreeError(w.device, "static scene build"));

  for (const Actor& a : w.pass.actors) {
    TriangleMesh m;
    if (a.kind == Actor::Kind::kCar)
      addCar(m, Eigen::Vector3d::Zero(), 0.0, a.shape, kLabelDynamic);
    else
      addPedestrian(m, Eigen::Vector3d::Zero(), kLabelDynamic);
    RTCScene s = meshScene(w.device, m, RTC_BUILD_QUALITY_MEDIUM);
    if (s == nullptr) return R::failure(embreeError(w.device, "actor scene build"));
    w.actor_scenes.push_back(s);
    w.actor_meshes.push_back(std::move(m));
  }
  if (rtcGetDeviceError(w.device) != RTC_ERROR_NONE)
    return R::failure(embreeError(w.device, "world build"));
  return world;
}

}  // namespace sim
}  // namespace gmm_localization
