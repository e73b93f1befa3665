#pragma once
// Simulation: one pass of the vehicle over a segment of the route, generating time-ordered
// sensor data for a sink (a rosbag writer, a KITTI writer, or memory for in-process tests).
//
// Typical use (in-process, no ROS):
//   SimulationConfig c = SimulationConfig::defaults(PassType::kDowntown);
//   c.town.size_x_m = c.town.size_y_m = 400; c.max_duration_s = 5; c.lidar.firing_decimation = 4;
//   auto sim = Simulation::create(c);            // Result<std::unique_ptr<Simulation>>
//   MemorySink mem; (*sim)->run(mem);             // mem.deskewed: scans in base_link + GT poses
//
// Times are trajectory times [s] from the start of the route; a ROS writer adds an epoch.

#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/hdl32e.h"
#include "gmm_localization/sim/ins_model.h"
#include "gmm_localization/sim/lidar_simulator.h"
#include "gmm_localization/sim/pass.h"
#include "gmm_localization/sim/rig.h"
#include "gmm_localization/sim/route.h"
#include "gmm_localization/sim/scan_merge.h"
#include "gmm_localization/sim/town.h"
#include "gmm_localization/sim/trajectory.h"
#include "gmm_localization/sim/world.h"

namespace gmm_localization {
namespace sim {

struct SimulationConfig {
  TownConfig town;
  RouteConfig route;
  KinematicsConfig kinematics;
  PassConfig pass;
  /// The nominal rig: what merging, deskewing and a writer's /tf_static use.
  RigConfig rig = RigConfig::fourRoofCorners();
  /// Calibration error: rays are cast from perturbedRig(rig, extrinsic_error), the true mounts
  /// (Simulation::lidar().rig()), so the outputs carry the error a miscalibrated vehicle has.
  ExtrinsicErrorConfig extrinsic_error;
  Hdl32eConfig lidar;
  InsConfig ins;
  /// Segment of the route: start [m along the route], and the first of distance/duration
  /// limits to be reached (<= 0 or infinity: to the end of the route).
  double start_offset_m = 0.0;
  double max_distance_m = std::numeric_limits<double>::infinity();
  double max_duration_s = std::numeric_limits<double>::infinity();
  double ground_truth_rate_hz = 100.0;
  uint64_t noise_seed = 1;  ///< LIDAR noise
  int threads = 2;
  /// Which scan products to compute (merging and deskewing cost time).
  bool emit_revolutions = true;
  bool emit_merged = true;
  bool emit_deskewed = false;

  /// Defaults for a pass type: pass contents, and per-pass seeds for kinematics (speeds,
  /// stops, lane wander), LIDAR noise, INS and the extrinsic error, so passes over the same
  /// town differ.
  static SimulationConfig defaults(PassType type, uint64_t pass_seed = 1);
  Status validate() const;
};

/// A scan deskewed with ground truth into base_link at its stamp, with the true pose.
struct DeskewedScan {
  int64_t index = 0;
  double stamp = 0.0;
  Eigen::Isometry3d base_to_map = Eigen::Isometry3d::Identity();
  std::vector<LidarPoint> points;
};

/// Receives data in non-decreasing order of availability time (revolution end for scans,
/// sample time otherwise). A failing Status stops the run with that reason.
class SimulationSink {
 public:
  virtual ~SimulationSink() = default;
  virtual Status onRevolution(const SensorRevolution&) { return Status::success(); }
  virtual Status onMergedScan(const MergedScan&) { return Status::success(); }
  virtual Status onDeskewedScan(const DeskewedScan&) { return Status::success(); }
  virtual Status onGroundTruth(const VehicleState&) { return Status::success(); }
  virtual Status onOdometry(const OdomSample&) { return Status::success(); }
  virtual Status onImu(const ImuSample&) { return Status::success(); }
};

/// Keeps everything in memory (short segments only).
class MemorySink : public SimulationSink {
 public:
  std::vector<SensorRevolution> revolutions;
  std::vector<MergedScan> merged;
  std::vector<DeskewedScan> deskewed;
  std::vector<VehicleState> ground_truth;
  std::vector<OdomSample> odometry;
  std::vector<ImuSample> imu;
  Status onRevolution(const SensorRevolution& r) override {
    revolutions.push_back(r);
    return Status::success();
  }
  Status onMergedScan(const MergedScan& s) override {
    merged.push_back(s);
    return Status::success();
  }
  Status onDeskewedScan(const DeskewedScan& s) override {
    deskewed.push_back(s);
    return Status::success();
  }
  Status onGroundTruth(const VehicleState& s) override {
    ground_truth.push_back(s);
    return Status::success();
  }
  Status onOdometry(const OdomSample& s) override {
    odometry.push_back(s);
    return Status::success();
  }
  Status onImu(const ImuSample& s) override {
    imu.push_back(s);
    return Status::success();
  }
};

struct SimulationStats {
  double sim_seconds = 0.0;
  double wall_seconds = 0.0;
  double lidar_wall_seconds = 0.0;  ///< ray casting, merging, deskewing (background thread)
  size_t rays = 0, points = 0, cycles = 0;
  double realTimeFactor() const { return wall_seconds > 0.0 ? sim_seconds / wall_seconds : 0.0; }
};

class Simulation {
 public:
  static Result<std::unique_ptr<Simulation>> create(const SimulationConfig& config);
  ~Simulation();

  const SimulationConfig& config() const { return config_; }
  const Town& town() const { return *town_; }
  const Route& route() const { return *route_; }
  const Trajectory& trajectory() const { return *trajectory_; }
  const World& world() const { return *world_; }
  /// The ray caster; lidar().rig() is the true (perturbed) rig, config().rig the nominal one.
  const LidarSimulator& lidar() const { return *lidar_; }
  /// Segment [begin, end] in trajectory time, and the cycles (merged scans) inside it.
  double beginTime() const { return t_begin_; }
  double endTime() const { return t_end_; }
  int64_t firstCycle() const { return first_cycle_; }
  int64_t numCycles() const { return num_cycles_; }

  /// Generates the segment. `progress` (optional) gets the fraction done after each cycle.
  Result<SimulationStats> run(SimulationSink& sink,
                              const std::function<void(double)>& progress = {}) const;

 private:
  Simulation() = default;
  SimulationConfig config_;
  std::unique_ptr<Town> town_;
  std::unique_ptr<Route> route_;
  std::unique_ptr<Trajectory> trajectory_;
  std::shared_ptr<World> world_;
  std::unique_ptr<LidarSimulator> lidar_;
  double t_begin_ = 0.0, t_end_ = 0.0;
  int64_t first_cycle_ = 0, num_cycles_ = 0;
};

}  // namespace sim
}  // namespace gmm_localization
