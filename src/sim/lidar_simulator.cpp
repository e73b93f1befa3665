#include "gmm_localization/sim/lidar_simulator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "firing_poses.h"
#include "gmm_localization/sim/random.h"
#include "lidar_response.h"
#include "parallel.h"
#include "world_impl.h"

namespace gmm_localization {
namespace sim {
namespace {

constexpr int kLasers = Hdl32eModel::kLasers;
constexpr int kBatchFirings = 16;
constexpr int kChunksPerRevolution = 8;

/// Distance along the ray to the ego box, or +inf.
float boxHit(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < box.min()[k] || o[k] > box.max()[k]) return std::numeric_limits<float>::infinity();
      continue;
    }
    double a = (box.min()[k] - o[k]) / d[k], b = (box.max()[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1 ? static_cast<float>(t0) : std::numeric_limits<float>::infinity();
}

}  // namespace

struct LidarSimulator::Task {
  int sensor;
  int64_t index;
  double t_start;
  const WorldSnapshot* snapshot;
  int f0, f1;
  LidarPoint* slots;  // per firing x laser of the whole revolution
  uint8_t* valid;
};

LidarSimulator::LidarSimulator(std::shared_ptr<const World> world, const Trajectory& trajectory,
                               RigConfig rig, const Hdl32eConfig& config, uint64_t noise_seed,
                               int threads)
    : world_(std::move(world)),
      trajectory_(trajectory),
      rig_(std::move(rig)),
      model_(config),
      seed_(noise_seed),
      threads_(std::max(1, threads)) {
  const int n = model_.firingsPerRevolution();
  for (const SensorMount& m : rig_.sensors) {
    std::vector<float> ranges(static_cast<size_t>(n) * kLasers);
    for (int f = 0; f < n; ++f) {
      for (int l = 0; l < kLasers; ++l) {
        const Eigen::Vector3d d = m.base_to_sensor.linear() * model_.direction(f, l).cast<double>();
        float r = std::numeric_limits<float>::infinity();
        for (const Eigen::AlignedBox3d& b : rig_.ego_boxes)
          r = std::min(r, boxHit(b, m.base_to_sensor.translation(), d));
        ranges[f * kLasers + l] = r;
      }
    }
    self_range_.push_back(std::move(ranges));
  }
}

LidarSimulator::~LidarSimulator() = default;

double LidarSimulator::revolutionStart(int sensor, int64_t index) const {
  return rig_.sensors[sensor].phase_s + static_cast<double>(index) * model_.revolutionPeriod();
}

std::vector<SensorRevolution> LidarSimulator::simulateCycle(int64_t index) const {
  std::vector<int> all(rig_.sensors.size());
  for (size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  return run(all, index);
}

SensorRevolution LidarSimulator::simulate(int sensor, int64_t index) const {
  return run({sensor}, index).front();
}

std::vector<SensorRevolution> LidarSimulator::run(const std::vector<int>& sensors,
                                                  int64_t index) const {
  const int n = model_.firingsPerRevolution();
  const double period = model_.revolutionPeriod();
  std::vector<std::unique_ptr<WorldSnapshot>> snaps;
  // Scratch slots (one per ray) are kept between calls: no page faults per revolution.
  std::lock_guard<std::mutex> lock(scratch_mutex_);
  std::vector<std::vector<LidarPoint>>& slots = slot_scratch_;
  std::vector<std::vector<uint8_t>>& valid = valid_scratch_;
  if (slots.size() < sensors.size()) {
    slots.resize(sensors.size());
    valid.resize(sensors.size());
  }
  std::vector<Task> tasks;
  for (size_t k = 0; k < sensors.size(); ++k) {
    const double t0 = revolutionStart(sensors[k], index);
    const Eigen::Vector2d center = trajectory_.pose(t0 + 0.5 * period).translation().head<2>();
    snaps.push_back(std::make_unique<WorldSnapshot>(*world_, t0, t0 + period, center,
                                                    model_.config().max_range_m + 20.0));
    slots[k].resize(static_cast<size_t>(n) * kLasers);
    valid[k].assign(static_cast<size_t>(n) * kLasers, 0);  // same size: no reallocation
    for (int c = 0; c < kChunksPerRevolution; ++c) {
      tasks.push_back({sensors[k], index, t0, snaps.back().get(), n * c / kChunksPerRevolution,
                       n * (c + 1) / kChunksPerRevolution, slots[k].data(), valid[k].data()});
    }
  }
  parallelFor(static_cast<int>(tasks.size()), threads_, [&](int k) { trace(tasks[k]); });

  std::vector<SensorRevolution> out(sensors.size());
  for (size_t k = 0; k < sensors.size(); ++k) {
    SensorRevolution& rev = out[k];
    rev.sensor = sensors[k];
    rev.index = index;
    rev.t_start = revolutionStart(sensors[k], index);
    rev.t_end = rev.t_start + period;
    rev.rays = static_cast<size_t>(n) * kLasers;
    size_t count = 0;
    for (uint8_t v : valid[k]) count += v;
    rev.points.reserve(count);
    for (size_t i = 0; i < rev.rays; ++i)
      if (valid[k][i]) rev.points.push_back(slots[k][i]);
  }
  return out;
}

void LidarSimulator::trace(const Task& task) const {
  const World::Impl& w = world_->impl();
  const Hdl32eConfig& cfg = model_.config();
  const PassConfig& pass = w.pass.config;
  const SensorMount& mount = rig_.sensors[task.sensor];
  const std::vector<float>& self = self_range_[task.sensor];
  const WorldSnapshot& snap = *task.snapshot;
  const float span = static_cast<float>(snap.t1() - snap.t0());
  std::vector<RTCRayHit> rays(kBatchFirings * kLasers);
  std::vector<float> far(kBatchFirings * kLasers);
  std::vector<RTCRayHit> again;
  std::vector<int> again_index;
  FiringPoses poses(trajectory_, mount.base_to_sensor, task.t_start, model_.firingPeriod());
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;

  for (int fb = task.f0; fb < task.f1; fb += kBatchFirings) {
    const int nf = std::min(kBatchFirings, task.f1 - fb);
    const int nr = nf * kLasers;
    for (int q = 0; q < nf; ++q) {
      const int f = fb + q;
      const double tf = task.t_start + f * model_.firingPeriod();
      const Eigen::Isometry3d t_ws = poses.at(f);
      const Eigen::Matrix3f rot = t_ws.linear().cast<float>();
      const Eigen::Vector3f org = t_ws.translation().cast<float>();
      const float time = std::clamp(static_cast<float>(tf - snap.t0()) / span, 0.0f, 1.0f);
      for (int l = 0; l < kLasers; ++l) {
        RTCRayHit& r = rays[q * kLasers + l];
        const Eigen::Vector3f d = rot * model_.direction(f, l);
        r.ray.org_x = org.x();
        r.ray.org_y = org.y();
        r.ray.org_z = org.z();
        r.ray.dir_x = d.x();
        r.ray.dir_y = d.y();
        r.ray.dir_z = d.z();
        r.ray.tnear = 0.02f;
        r.ray.tfar = far[q * kLasers + l] =
            std::min(static_cast<float>(cfg.max_range_m), self[f * kLasers + l]);
        r.ray.time = time;
        r.ray.mask = 0xFFFFFFFFu;
        r.ray.id = 0;
        r.ray.flags = 0;
        r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
    }
    snap.intersect(&ctx, rays.data(), static_cast<unsigned>(nr));

    // Porous canopies: some rays continue through foliage (at most two layers).
    for (int round = 0; round < 2; ++round) {
      again.clear();
      again_index.clear();
      for (int i = 0; i < nr; ++i) {
        RTCRayHit& r = rays[i];
        if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        Material m;
        uint8_t label;
        Eigen::Vector3f n;
        snap.surface(r.hit, &m, &label, &n);
        const float pass_p = materialResponse(m).pass_through;
        if (pass_p <= 0.0f) continue;
        const int f = fb + i / kLasers, l = i % kLasers;
        if (hashUniform(seed_, task.sensor, task.index, f * kLasers + l, 0xF0 + round) >= pass_p)
          continue;
        RTCRayHit c = r;
        c.ray.tnear = r.ray.tfar + 0.05f;
        c.ray.tfar = far[i];
        c.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        c.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        if (c.ray.tnear >= c.ray.tfar) {
          r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          continue;
        }
        again.push_back(c);
        again_index.push_back(i);
      }
      if (again.empty()) break;
      snap.intersect(&ctx, again.data(), static_cast<unsigned>(again.size()));
      for (size_t k = 0; k < again.size(); ++k) rays[again_index[k]] = again[k];
    }

    for (int i = 0; i < nr; ++i) {
      const RTCRayHit& r = rays[i];
      const int f = fb + i / kLasers, l = i % kLasers;
      const size_t slot = static_cast<size_t>(f) * kLasers + l;
      const uint64_t key = hashKeys(seed_, task.sensor, task.index, slot);
      const bool hit = r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
      Return ret{false, 0.0f, 0.0f};
      uint8_t label = kLabelStatic;
      if (pass.snow && pass.snowfall_returns_per_ray > 0.0 &&
          unitFromHash(splitMix64(key ^ 0x5A0F)) < pass.snowfall_returns_per_ray) {
        const double u = unitFromHash(splitMix64(key ^ 0x5A1F));
        const float d = static_cast<float>(1.0 - pass.snowfall_mean_range_m * std::log(1.0 - u));
        // tfar is the surface hit, or the ego body / maximum range when nothing was hit.
        if (d < pass.snowfall_max_range_m && d < r.ray.tfar && d >= cfg.min_range_m) {
          ret = flakeResponse(cfg, key, d);
          label = kLabelSnow;
        }
      }
      if (!ret.detected && hit && r.ray.tfar >= cfg.min_range_m) {
        Material m;
        Eigen::Vector3f n;
        snap.surface(r.hit, &m, &label, &n);
        const Eigen::Vector3f d(r.ray.dir_x, r.ray.dir_y, r.ray.dir_z);
        const float cos_inc = std::abs(n.normalized().dot(d));
        if (m == Material::kAsphalt) {  // paint, or a repaved stretch (map aging)
          const float x = r.ray.org_x + r.ray.tfar * d.x(), y = r.ray.org_y + r.ray.tfar * d.y();
          m = roadSurfaceAt(*w.town, w.aging, x, y);
        }
        ret = lidarResponse(cfg, key, m, r.ray.tfar, cos_inc);
      }
      if (!ret.detected || ret.range_m < cfg.min_range_m || ret.range_m > cfg.max_range_m) continue;
      const Eigen::Vector3f p = model_.direction(f, l) * ret.range_m;
      task.slots[slot] = {p.x(),
                          p.y(),
                          p.z(),
                          ret.intensity,
                          static_cast<float>(model_.pointTime(f, l)),
                          static_cast<uint16_t>(Hdl32eModel::ringOfLaser(l)),
                          label};
      task.valid[slot] = 1;
    }
  }
}

}  // namespace sim
}  // namespace gmm_localization
