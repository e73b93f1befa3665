#include "kitti_check/kitti_check_register.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>

#include "bench/bench_data.h"
#include "bench/bench_peers.h"
#include "evaluate/evaluate_integrity.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/raster_region.h"

namespace gmm_localization {
namespace kitti_check {

using bench::angleDiff;
using bench::yawOf;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Process CPU time [s]: every matcher here runs on the calling thread, so this is its CPU
/// time, unaffected by other processes competing for the cores.
double cpuNow() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Share of the scan's 0.2 m voxels (placed at the truth) over cells with a mixture.
double overlapShare(const GmmMap& map, const Keyframe& k) {
  const PointList vox = voxelDownsample(k.points, 0.2);
  size_t on = 0, n = 0;
  for (const Eigen::Vector3f& p : vox) {
    if (!p.allFinite()) continue;
    const Eigen::Vector3d q = k.truth * p.cast<double>();
    const GaussianMixture1D* g = map.cell(map.geometry().cellAt(q.x(), q.y()));
    ++n;
    on += (g != nullptr && !g->empty());
  }
  return n > 0 ? static_cast<double>(on) / n : 0.0;
}

struct Peer {
  std::string name;
  std::unique_ptr<bench::PeerMatcher> matcher;
};

/// Runs ours (when reg is given) and the peers from one prior, appending a trial each.
void runPrior(const Registration* reg, const ChunkMap& raster, std::vector<Peer>& peers,
              const Keyframe& k, const WindowSpec& w, const std::string& window_name,
              const Pose6& prior, std::vector<Trial>& out) {
  Trial base;
  base.keyframe = k.index;
  base.window = window_name;
  poseErrors(toIsometry(prior), k.truth, base);
  base.offset_m = base.error_m;
  base.offset_deg = base.error_deg;

  Trial ours = base;
  ours.matcher = "ours";
  MatchRequest req;
  req.prior = prior;
  req.half_x_m = req.half_y_m = w.half_m;
  req.half_heading_rad = w.half_deg * M_PI / 180.0;
  req.has_reference = true;
  req.reference = fromIsometry(k.truth);
  if (reg != nullptr) {
    const double c0 = cpuNow(), t0 = now();
    auto r = reg->match(raster, k.points, req, nullptr, now, &ours.stages);
    ours.seconds = now() - t0;
    ours.cpu_seconds = cpuNow() - c0;
    ours.matched = r.ok();
    if (r.ok()) {
      ours.evaluations_fraction = r->search.stats.fraction();
      ours.integrity = eval::integrityOf(*r);
      ours.integrity.certificate_ms = 1e3 * ours.stages.certificate_s;
      poseErrors(toIsometry(r->pose), k.truth, ours);
      Trial discrete;
      poseErrors(toIsometry(r->search.pose), k.truth, discrete);
      ours.discrete_error_m = discrete.error_m;
      ours.discrete_error_long_m = discrete.error_long_m;
      ours.discrete_error_lat_m = discrete.error_lat_m;
    } else {
      ours.failure = r.error();
    }
    out.push_back(ours);
  }

  for (Peer& p : peers) {
    Trial t = base;
    t.matcher = p.name;
    const double c0 = cpuNow();
    const bench::PeerResult pr = p.matcher->align(k.points, toIsometry(prior));
    t.cpu_seconds = cpuNow() - c0;
    t.seconds = pr.seconds;
    t.matched = pr.pose.matrix().allFinite();
    if (!pr.converged) t.failure = "not converged";
    poseErrors(pr.pose, k.truth, t);
    out.push_back(t);
  }
}

}  // namespace

std::vector<WindowSpec> defaultWindows() {
  WindowSpec paper;
  paper.name = "paper window 25 m x 25 m, +-15 deg";
  WindowSpec tracking;
  tracking.name = "tracking window +-2 m, +-3 deg";
  tracking.half_m = 2.0;
  tracking.half_deg = 3.0;
  tracking.offset_m = 1.5;
  tracking.offset_deg = 2.5;
  return {paper, tracking};
}

void poseErrors(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& truth, Trial& t) {
  const Eigen::Vector3d d = pose.translation() - truth.translation();
  t.error_m = d.head<2>().norm();
  t.error_z_m = std::abs(d.z());
  const double h = yawOf(truth);
  t.error_long_m = d.x() * std::cos(h) + d.y() * std::sin(h);
  t.error_lat_m = -d.x() * std::sin(h) + d.y() * std::cos(h);
  t.error_deg = std::abs(angleDiff(yawOf(pose), yawOf(truth))) * 180.0 / M_PI;
}

Result<LooReport> runLeaveOneOut(const LooOptions& o) {
  using R = Result<LooReport>;
  auto set = loadKeyframes(o.data);
  if (!set.ok()) return R::failure(set.error());
  const auto& keyframes = set->keyframes;
  noteData(set->data, stderr);
  const std::vector<WindowSpec> windows = o.windows.empty() ? defaultWindows() : o.windows;
  const Registration reg(o.registration);
  const Registration* ours = o.ours ? &reg : nullptr;
  LooReport report;
  report.data = set->data;
  for (const Keyframe& k : keyframes) {
    if (!o.held_out.empty() &&
        std::find(o.held_out.begin(), o.held_out.end(), k.index) == o.held_out.end()) {
      continue;
    }
    Fold fold;
    fold.keyframe = k.index;
    fold.nearest_map_keyframe_m = 1e9;
    for (const Keyframe& m : keyframes) {
      if (m.index == k.index) continue;
      fold.map_keyframes.push_back(m.index);
      fold.nearest_map_keyframe_m =
          std::min(fold.nearest_map_keyframe_m,
                   (m.truth.translation() - k.truth.translation()).head<2>().norm());
    }
    const std::string map_dir = o.work_dir + "/loo_" + std::to_string(k.index);
    MapBuilderOptions map_options = defaultMapOptions(map_dir);
    map_options.blur_sigma_m = o.map_blur_sigma_m;
    map_options.geometry.origin_x_m += o.grid_shift_m;
    map_options.geometry.origin_y_m += o.grid_shift_m;
    auto built = buildMap(set->data, fold.map_keyframes, map_options);
    if (!built.ok()) return R::failure(built.error());
    auto store = MapStore::open(map_dir);
    if (!store.ok()) return R::failure(store.error());
    auto gmm = store->loadAll();
    if (!gmm.ok()) return R::failure(gmm.error());
    fold.map_cells = store->summary().nonEmptyCells();
    fold.overlap = overlapShare(gmm.value(), k);
    auto raster = rasterizeRegion(store.value(), o.raster,
                                  {PlanCentre(k.truth.translation().head<2>())}, o.raster_radius_m);
    if (!raster.ok()) return R::failure(raster.error());

    std::vector<Peer> peers;
    if (o.peers) {
      const PointList target = worldCloud(keyframes, fold.map_keyframes, o.peer_target_voxel_m);
      for (auto kind : {bench::PeerMatcher::Kind::kNdt, bench::PeerMatcher::Kind::kGicp}) {
        Peer p;
        p.matcher = std::make_unique<bench::PeerMatcher>(kind, o.peer);
        p.name = p.matcher->name();
        p.matcher->setTarget(target);
        peers.push_back(std::move(p));
      }
    }
    std::fprintf(stderr,
                 "keyframe %d: map from %zu keyframes (%llu cells), nearest mapped keyframe "
                 "%.1f m, overlap %.0f%%\n",
                 k.index, fold.map_keyframes.size(),
                 static_cast<unsigned long long>(fold.map_cells), fold.nearest_map_keyframe_m,
                 100.0 * fold.overlap);
    // From the SLAM pose itself: the bias of each matcher's optimum.
    runPrior(ours, raster.value(), peers, k, windows.front(), "SLAM pose", fromIsometry(k.truth),
             report.trials);
    for (size_t wi = 0; wi < windows.size(); ++wi) {
      const WindowSpec& w = windows[wi];
      std::mt19937 rng(o.seed * 1000003u + static_cast<uint32_t>(k.index) * 101u +
                       static_cast<uint32_t>(wi));
      for (int i = 0; i < o.offsets; ++i) {
        const Pose6 prior = offsetPrior(k.truth, w.offset_m, w.offset_deg * M_PI / 180.0, rng);
        runPrior(ours, raster.value(), peers, k, w, w.name, prior, report.trials);
      }
      std::fprintf(stderr, "keyframe %d: %s done (%d offsets)\n", k.index, w.name.c_str(),
                   o.offsets);
    }
    report.folds.push_back(fold);
  }
  return report;
}

}  // namespace kitti_check
}  // namespace gmm_localization
