#include "gmm_localization/sim/simulation.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

SimulationConfig SimulationConfig::defaults(PassType type, uint64_t pass_seed) {
  SimulationConfig c;
  c.pass = PassConfig::defaults(type, pass_seed);
  const uint64_t key = hashKeys(static_cast<uint64_t>(type), pass_seed);
  c.kinematics.seed = hashKeys(key, 0x4B1ull);
  c.noise_seed = hashKeys(key, 0x11Dull);
  c.ins.seed = hashKeys(key, 0x125ull);
  c.extrinsic_error.seed = hashKeys(key, 0xE47ull);
  return c;
}

Status SimulationConfig::validate() const {
  for (const Status& s : {town.validate(), route.validate(), kinematics.validate(), pass.validate(),
                          rig.validate(1.0 / lidar.rotation_rate_hz), extrinsic_error.validate(),
                          lidar.validate(), ins.validate()}) {
    if (!s) return s;
  }
  if (!(start_offset_m >= 0.0))
    return Status::failure("SimulationConfig.start_offset_m must be >= 0");
  if (!(ground_truth_rate_hz >= 1.0 && ground_truth_rate_hz <= 1000.0))
    return Status::failure("SimulationConfig.ground_truth_rate_hz must be in [1, 1000]");
  if (!(threads >= 1 && threads <= 64))
    return Status::failure("SimulationConfig.threads must be in [1, 64]");
  return Status::success();
}

Simulation::~Simulation() = default;

Result<std::unique_ptr<Simulation>> Simulation::create(const SimulationConfig& config) {
  using R = Result<std::unique_ptr<Simulation>>;
  const Status valid = config.validate();
  if (!valid) return R::failure(valid.error());
  std::unique_ptr<Simulation> sim(new Simulation());
  sim->config_ = config;
  auto town = Town::generate(config.town);
  if (!town) return R::failure(town.error());
  sim->town_ = std::make_unique<Town>(std::move(*town));
  auto route = Route::plan(*sim->town_, config.route);
  if (!route) return R::failure(route.error());
  sim->route_ = std::make_unique<Route>(std::move(*route));
  auto traj = Trajectory::create(*sim->town_, *sim->route_, config.kinematics);
  if (!traj) return R::failure(traj.error());
  sim->trajectory_ = std::make_unique<Trajectory>(std::move(*traj));
  auto world = World::create(*sim->town_, config.pass, config.threads);
  if (!world) return R::failure(world.error());
  sim->world_ = *world;
  // Rays leave the true mounts; run() merges and deskews with the nominal config.rig.
  sim->lidar_ = std::make_unique<LidarSimulator>(sim->world_, *sim->trajectory_,
                                                 perturbedRig(config.rig, config.extrinsic_error),
                                                 config.lidar, config.noise_seed, config.threads);

  const Trajectory& tr = *sim->trajectory_;
  if (config.start_offset_m >= tr.length())
    return R::failure("start_offset_m = " + std::to_string(config.start_offset_m) +
                      " is beyond the route length " + std::to_string(tr.length()) + " m");
  sim->t_begin_ = tr.timeAtDistance(config.start_offset_m);
  double t_end = tr.duration();
  if (config.max_distance_m > 0.0 && std::isfinite(config.max_distance_m))
    t_end = std::min(t_end, tr.timeAtDistance(config.start_offset_m + config.max_distance_m));
  if (config.max_duration_s > 0.0 && std::isfinite(config.max_duration_s))
    t_end = std::min(t_end, sim->t_begin_ + config.max_duration_s);
  sim->t_end_ = t_end;
  const double period = 1.0 / config.lidar.rotation_rate_hz;
  double min_phase = period, max_phase = 0.0;
  for (const SensorMount& m : config.rig.sensors) {
    min_phase = std::min(min_phase, m.phase_s);
    max_phase = std::max(max_phase, m.phase_s);
  }
  sim->first_cycle_ = static_cast<int64_t>(std::ceil((sim->t_begin_ - min_phase) / period - 1e-9));
  const int64_t last = static_cast<int64_t>(std::floor((t_end - max_phase) / period + 1e-9)) - 1;
  sim->num_cycles_ = std::max<int64_t>(0, last - sim->first_cycle_ + 1);
  return R(std::move(sim));
}

}  // namespace sim
}  // namespace gmm_localization
