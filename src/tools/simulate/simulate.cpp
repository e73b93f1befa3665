// simulate: generates a pass of the simulated downtown as a rosbag and/or a KITTI-style
// directory for build_map. See --help and docs/simulator.md.
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "common/cli_args.h"
#include "gmm_localization/sim/gnss_model.h"
#include "gmm_localization/sim/kitti_writer.h"
#include "gmm_localization/sim/map_pose_error.h"
#include "gmm_localization/sim/simulation.h"
#include "simulate/simulate_bag_writer.h"
#include "simulate/simulate_options.h"

using namespace gmm_localization;

namespace {

/// Sends every event to the bag and the KITTI writer.
class OutputSink : public sim::SimulationSink {
 public:
  tools::BagSink* bag = nullptr;
  sim::KittiWriter* kitti = nullptr;
  int kitti_every = 1;
  Status onRevolution(const sim::SensorRevolution& r) override {
    return bag ? bag->onRevolution(r) : Status::success();
  }
  Status onMergedScan(const sim::MergedScan& s) override {
    return bag ? bag->onMergedScan(s) : Status::success();
  }
  Status onGroundTruth(const sim::VehicleState& s) override {
    if (!bag) return Status::success();
    const Status g = gnssUpTo(s.t);
    return g ? bag->onGroundTruth(s) : g;
  }
  Status onOdometry(const sim::OdomSample& o) override {
    return bag ? bag->onOdometry(o) : Status::success();
  }
  Status onImu(const sim::ImuSample& m) override { return bag ? bag->onImu(m) : Status::success(); }
  Status onDeskewedScan(const sim::DeskewedScan& s) override {
    if (!kitti || (count_++ % kitti_every) != 0) return Status::success();
    truth.push_back(s.base_to_map);
    return kitti->write(s.points, s.base_to_map, s.stamp);
  }
  std::vector<Eigen::Isometry3d> truth;  // the poses written to poses.txt, in order
  // --gnss realistic: the receiver, its options and the trajectory its truth comes from.
  std::unique_ptr<sim::GnssModel> gnss;
  const tools::SimulateGnssOptions* gnss_options = nullptr;
  const sim::Trajectory* trajectory = nullptr;
  double epoch_s = 0.0;

 private:
  /// Writes the fixes stamped up to and including t (before the ground truth at t).
  Status gnssUpTo(double t) {
    if (!gnss) return Status::success();
    fixes_.clear();
    gnss->advanceTo(
        std::nextafter(t, HUGE_VAL),
        [this](double ft) { return trajectory->pose(ft).translation(); }, &fixes_);
    for (const sim::GnssSample& f : fixes_) {
      auto msg = tools::navSatFixFromSample(f, gnss_options->georeference, epoch_s);
      if (!msg) return Status::failure(msg.error());
      const Status w = bag->onGnssFix(gnss_options->topic, *msg);
      if (!w) return w;
    }
    return Status::success();
  }
  std::vector<sim::GnssSample> fixes_;
  long count_ = 0;
};

/// One line per sensor: how its true mount differs from the nominal one (the run log keeps
/// the drawn calibration error).
void printExtrinsicErrors(const sim::Simulation& s) {
  const sim::RigConfig& nominal = s.config().rig;
  const sim::RigConfig& truth = s.lidar().rig();
  for (size_t k = 0; k < nominal.sensors.size(); ++k) {
    const sim::MountError e = sim::mountError(nominal.sensors[k], truth.sensors[k]);
    const Eigen::Vector3d deg = e.rotation_rad * 180.0 / M_PI;
    std::printf(
        "extrinsic error %s: translation %+.4f %+.4f %+.4f m (%.4f m), rotation %+.3f %+.3f "
        "%+.3f deg (%.3f deg) about base_link x y z\n",
        nominal.sensors[k].frame_id.c_str(), e.translation_m.x(), e.translation_m.y(),
        e.translation_m.z(), e.translation_m.norm(), deg.x(), deg.y(), deg.z(), deg.norm());
  }
}

void printAging(const sim::World& world) {
  const sim::MapAging& a = world.aging();
  size_t with_container = 0;
  for (const sim::ConstructionSite& site : a.sites) with_container += site.has_container;
  double repaved_m = 0.0;
  size_t repainted = 0;
  for (const sim::RepavedStretch& r : a.repaved) {
    repaved_m += r.lateral.x() > 0.5 ? r.area.sizes().y() : r.area.sizes().x();  // along
    repainted += r.repainted;
  }
  std::printf(
      "aging: %zu construction sites (%zu with a container), %zu containers, %zu of %zu trees "
      "grown, %zu repaved stretches (%.0f m; %zu repainted shifted, %zu without paint); %zu "
      "parked cars removed\n",
      a.sites.size(), with_container, a.containers.size(), a.grown_trees.size(),
      world.town().trees().size(), a.repaved.size(), repaved_m, repainted,
      a.repaved.size() - repainted, a.removed_parked_cars);
}

int fail(const std::string& what) {
  std::fprintf(stderr, "simulate: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  tools::NormalizedArgs args(argc, argv);
  auto parsed = tools::parseSimulateOptions(args.argc(), args.argv());
  if (!parsed) {
    fail(parsed.error() + "\n(simulate --help lists the options)");
    return tools::kExitUsage;
  }
  const tools::SimulateOptions& opt = *parsed;
  if (opt.help) {
    std::fputs(tools::simulateHelp(), stdout);
    return 0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto created = sim::Simulation::create(opt.config);
  if (!created) return fail(created.error());
  const sim::Simulation& s = **created;
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto& tc = s.town().config();
  std::printf(
      "town: seed %llu, %.0f x %.0f m grid, %d x %d intersections, %zu static triangles (built in "
      "%.1f s)\n",
      static_cast<unsigned long long>(tc.seed), tc.size_x_m, tc.size_y_m, s.town().nodesX(),
      s.town().nodesY(), s.world().numStaticTriangles(), build_s);
  std::printf(
      "route: %.0f m, %zu intersections, %.0f%% of its road length driven in both directions, %.0f "
      "s\n",
      s.route().length(), s.route().nodes().size(), 100.0 * s.route().bothDirectionsShare(),
      s.trajectory().duration());
  std::printf(
      "pass: %s, %zu parked cars, %zu actors; segment t = [%.1f, %.1f] s, %lld scans; %zu "
      "sensor(s), "
      "azimuth step %.3f deg\n",
      sim::passTypeName(opt.config.pass.type), s.world().pass().parked.size(),
      s.world().pass().actors.size(), s.beginTime(), s.endTime(),
      static_cast<long long>(s.numCycles()), opt.config.rig.sensors.size(),
      s.lidar().model().azimuthStepDeg());
  if (opt.config.extrinsic_error.mode != sim::ExtrinsicErrorMode::kNone) printExtrinsicErrors(s);
  if (opt.config.pass.aging.mode != sim::MapAgingMode::kNone) printAging(s.world());
  if (opt.gnss.config.mode != sim::GnssMode::kNone) {
    std::printf("%s\n", tools::describeGnss(opt.gnss).c_str());
  }
  if (opt.dry_run) return 0;

  OutputSink out;
  std::unique_ptr<tools::BagSink> bag;
  std::unique_ptr<sim::KittiWriter> kitti;
  if (!opt.bag.path.empty()) {
    auto b = tools::BagSink::open(opt.bag, opt.config, s.beginTime());
    if (!b) return fail(b.error());
    bag = std::move(*b);
    out.bag = bag.get();
    if (opt.gnss.config.mode != sim::GnssMode::kNone) {
      out.gnss = std::make_unique<sim::GnssModel>(opt.gnss.config, s.beginTime());
      out.gnss_options = &opt.gnss;
      out.trajectory = &s.trajectory();
      out.epoch_s = opt.bag.epoch_s;
    }
  }
  if (!opt.kitti_dir.empty()) {
    auto k = sim::KittiWriter::open(opt.kitti_dir, opt.kitti_labels);
    if (!k) return fail(k.error());
    kitti = std::move(*k);
    out.kitti = kitti.get();
    out.kitti_every = opt.kitti_every;
  }
  const auto wall0 = std::chrono::steady_clock::now();
  double next_report = 0.05;
  auto progress = [&](double f) {
    if (opt.quiet || f < next_report) return;
    next_report += 0.05;
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    const double simt = f * (s.endTime() - s.beginTime());
    std::fprintf(stderr, "  %3.0f%%  sim %.1f s  wall %.1f s  %.2fx real time  ETA %.0f s\n",
                 100.0 * f, simt, wall, simt / std::max(1e-9, wall),
                 wall * (1.0 - f) / std::max(1e-9, f));
  };
  auto stats = s.run(out, progress);
  if (!stats) return fail(stats.error());
  if (bag) {
    const Status c = bag->close();
    if (!c) return fail(c.error());
  }
  if (kitti) {
    const Status c = kitti->close();
    if (!c) return fail(c.error());
    if (opt.map_pose_error.mode != sim::MapPoseErrorMode::kNone) {
      // Keep the truth beside the SLAM-like poses that build_map will read.
      const Status t = sim::KittiWriter::writePoses(opt.kitti_dir + "/poses_truth.txt", out.truth);
      if (!t) return fail(t.error());
      const sim::MapPoseError model(opt.map_pose_error);
      const Status p =
          sim::KittiWriter::writePoses(opt.kitti_dir + "/poses.txt", model.apply(out.truth));
      if (!p) return fail(p.error());
      if (!opt.quiet)
        std::printf("map poses: realistic error, %zu loop-closure scans; truth in %s\n",
                    model.closures(out.truth).size(), (opt.kitti_dir + "/poses_truth.txt").c_str());
    }
  }
  const sim::SimulationStats& st = *stats;
  std::printf(
      "generated %.1f s of driving in %.1f s wall: %.2fx real time (ray casting alone %.2fx); %zu "
      "rays, "
      "%zu points, %zu scans\n",
      st.sim_seconds, st.wall_seconds, st.realTimeFactor(),
      st.sim_seconds / std::max(1e-9, st.lidar_wall_seconds), st.rays, st.points, st.cycles);
  if (bag) {
    struct stat sb {};
    if (stat(opt.bag.path.c_str(), &sb) == 0) {
      const double mb = sb.st_size / 1e6;
      std::printf("bag: %s, %.1f MB, %.0f MB per minute of driving\n", opt.bag.path.c_str(), mb,
                  mb / std::max(1e-9, st.sim_seconds / 60.0));
    }
  }
  if (kitti) std::printf("kitti: %s, %zu scans\n", opt.kitti_dir.c_str(), kitti->scans());
  return 0;
}
