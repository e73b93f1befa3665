// bench_registration: the registration benchmark. Prints markdown tables of search
// time, evaluations and equality with the exhaustive search for the paper's window and a
// tracking window, success and time of PCL NDT and GICP from the same offsets, and time against
// scan size. All numbers come from this run, as ratios where the machine's noise matters.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <random>
#include <string>
#include <thread>

#include "bench_data.h"
#include "bench_peers.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/registration.h"

using namespace gmm_localization;
using namespace gmm_localization::bench;

namespace {

/// The 1-minute load average: times are only comparable on an otherwise idle machine.
std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one;
  return (in >> one) ? one : std::string("unknown");
}

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Options {
  std::string map_dir, scans_dir, mapping_dir;
  int count = 30;
  int exhaustive_every = 3;  // exhaustive reference on every n-th scan of each window
  int peer_count = 20;
  uint32_t seed = 1;
  double offset_m = 10.0, offset_deg = 15.0;
  double raster_radius_m = 110.0;
  bool sizes = true;
  bool global = true;
  int global_count = 10;
  std::vector<double> global_regions_m = {25.0, 50.0, 100.0};
  RegistrationOptions reg;
  RasterOptions raster;
};

void usage() {
  std::printf(
      "bench_registration --map DIR --scans KITTI_DIR [--mapping KITTI_DIR] [options]\n"
      "  --map DIR            Gaussian mixture map (build_map output)\n"
      "  --scans DIR          localization scans with ground-truth poses (simulate --kitti)\n"
      "  --mapping DIR        mapping-pass scans: target clouds for PCL NDT/GICP (optional)\n"
      "  --count N            test scans (30)\n"
      "  --peer-count N       scans for the NDT/GICP comparison (20; 0 = skip)\n"
      "  --exhaustive-every N check branch-and-bound against exhaustive on every N-th scan (3)\n"
      "  --offset-m M         initial offsets uniform in a disc of this radius (10)\n"
      "  --offset-deg D       and within +-D degrees of heading (15)\n"
      "  --seed N             offset seed (1)\n"
      "  --heading-step-deg D search heading step (0.5)\n"
      "  --max-points N       search points after voxelling (registration default)\n"
      "  --voxel M            search voxel (registration default)\n"
      "  --ground-share S     largest share of ground points among search points (default)\n"
      "  --z-period N         raster z coarsening period (raster default)\n"
      "  --layers N           raster layers (raster default)\n"
      "  --refine-points N    points the hill climb scores (registration default)\n"
      "  --global-count N     scans per global-localization row (10; first N of the test scans)\n"
      "  --global-regions A,B square region edges of the global rows [m] (25,50,100)\n"
      "  --global-points N    search points of the global search (registration default)\n"
      "  --global-budget N    node scores the global search may compute (default: unbounded)\n"
      "  --global-root-headings L  root heading intervals of 2^L headings (default)\n"
      "  --global-split-share S    heading-vs-translation split rule (default)\n"
      "  --no-global          skip the global-localization table\n"
      "  --no-sizes           skip the scan-size table\n");
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") return false;
    if (a == "--no-sizes") {
      o.sizes = false;
      continue;
    }
    if (a == "--no-global") {
      o.global = false;
      continue;
    }
    if ((v = next()) == nullptr) {
      std::fprintf(stderr, "option %s needs a value\n", a.c_str());
      return false;
    }
    if (a == "--map")
      o.map_dir = v;
    else if (a == "--scans")
      o.scans_dir = v;
    else if (a == "--mapping")
      o.mapping_dir = v;
    else if (a == "--count")
      o.count = std::atoi(v);
    else if (a == "--global-count")
      o.global_count = std::atoi(v);
    else if (a == "--global-regions") {
      o.global_regions_m.clear();
      for (const char* q = v; *q != '\0';) {
        char* end = nullptr;
        o.global_regions_m.push_back(std::strtod(q, &end));
        if (end == q) break;
        q = *end == ',' ? end + 1 : end;
      }
    } else if (a == "--global-points")
      o.reg.global.max_points = static_cast<size_t>(std::atoi(v));
    else if (a == "--global-budget")
      o.reg.global.max_evaluations = std::atoll(v);
    else if (a == "--global-root-headings")
      o.reg.global.root_heading_levels = std::atoi(v);
    else if (a == "--global-split-share")
      o.reg.global.heading_split_share = std::atof(v);
    else if (a == "--peer-count")
      o.peer_count = std::atoi(v);
    else if (a == "--exhaustive-every")
      o.exhaustive_every = std::atoi(v);
    else if (a == "--offset-m")
      o.offset_m = std::atof(v);
    else if (a == "--offset-deg")
      o.offset_deg = std::atof(v);
    else if (a == "--seed")
      o.seed = static_cast<uint32_t>(std::atoi(v));
    else if (a == "--heading-step-deg")
      o.reg.heading_step_rad = std::atof(v) * M_PI / 180.0;
    else if (a == "--max-points")
      o.reg.filter.max_points = static_cast<size_t>(std::atoi(v));
    else if (a == "--voxel")
      o.reg.filter.voxel_m = std::atof(v);
    else if (a == "--ground-share")
      o.reg.filter.ground_share = std::atof(v);
    else if (a == "--z-period")
      o.raster.z_coarsening_period = std::atoi(v);
    else if (a == "--refine-points")
      o.reg.refine_max_points = static_cast<size_t>(std::atoi(v));
    else if (a == "--layers")
      o.raster.num_layers = std::atoi(v);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return false;
    }
  }
  if (o.map_dir.empty() || o.scans_dir.empty()) {
    std::fprintf(stderr, "--map and --scans are required\n");
    return false;
  }
  return true;
}

struct WindowRow {
  std::string name;
  std::vector<double> filter_ms, search_ms, filter_search_ms, total_ms, fraction, error_m,
      error_deg;
  std::vector<double> refine_ms, covariance_ms, obstacles_ms, certificate_ms;
  std::vector<double> points, lookups;
  int certified = 0, certified_wrong = 0;  // certified matches; of them outside success  // search
                                           // points per heading; evaluations x points
  int success = 0, runs = 0, equal = 0, compared = 0, failures = 0;
  std::vector<double> exhaustive_ms;
};

bool success(double err_m, double err_deg) { return err_m < 0.5 && err_deg < 1.0; }

void runWindow(const Options& o, const ChunkMap& map, const std::vector<BenchScan>& scans,
               double half_m, double half_deg, double off_m, double off_deg, WindowRow& row) {
  const Registration reg(o.reg);
  std::mt19937 rng(o.seed);
  // The exhaustive reference runs after the timed pass: seconds of it between matches would
  // flush the caches that a vehicle's consecutive matches share.
  struct Check {
    size_t scan;
    MatchRequest request;
    SearchOutcome branch_and_bound;
  };
  std::vector<Check> checks;
  for (size_t i = 0; i < scans.size(); ++i) {
    const BenchScan& s = scans[i];
    MatchRequest req;
    req.prior = offsetPrior(s.truth, off_m, off_deg * M_PI / 180.0, rng);
    req.half_x_m = req.half_y_m = half_m;
    req.half_heading_rad = half_deg * M_PI / 180.0;
    ++row.runs;
    const double t0 = now();
    auto prepared = reg.prepare(map, s.points, req);
    if (!prepared.ok()) {
      ++row.failures;
      std::fprintf(stderr, "scan %d: %s\n", s.index, prepared.error().c_str());
      continue;
    }
    const double t1 = now();
    bool complete = true;
    const SearchOutcome bb = reg.search(prepared->problem, nullptr, &complete);
    const double t2 = now();
    if (!complete) {
      ++row.failures;
      std::fprintf(stderr, "scan %d: search stopped at its budget\n", s.index);
      continue;
    }
    if (o.exhaustive_every > 0 && i % o.exhaustive_every == 0) checks.push_back({i, req, bb});
    const double n = static_cast<double>(prepared->problem.points(0).size());
    const double t3 = now();
    RegistrationTiming timing;
    auto r = reg.finish(map, s.points, req, std::move(prepared.value()), bb, now, &timing);
    const double t4 = now();
    row.refine_ms.push_back(timing.refine_s * 1e3);
    row.covariance_ms.push_back(timing.covariance_s * 1e3);
    row.certificate_ms.push_back(timing.certificate_s * 1e3);
    row.obstacles_ms.push_back(timing.obstacles_s * 1e3);
    row.filter_ms.push_back((t1 - t0) * 1e3);
    row.search_ms.push_back((t2 - t1) * 1e3);
    row.filter_search_ms.push_back((t2 - t0) * 1e3);
    row.total_ms.push_back((t2 - t0 + t4 - t3) * 1e3);
    row.fraction.push_back(bb.stats.fraction());
    row.points.push_back(n);
    row.lookups.push_back(n * bb.stats.evaluations);
    if (!r.ok()) {
      ++row.failures;
      std::fprintf(stderr, "scan %d: %s\n", s.index, r.error().c_str());
      continue;
    }
    const Pose6 t = fromIsometry(s.truth);
    const double e = std::hypot(r->pose.x - t.x, r->pose.y - t.y);
    const double eh = std::abs(angleDiff(r->pose.yaw, t.yaw)) * 180.0 / M_PI;
    row.error_m.push_back(e);
    row.error_deg.push_back(eh);
    row.success += success(e, eh);
    if (r->certificate.certified) {
      ++row.certified;
      row.certified_wrong += success(e, eh) ? 0 : 1;
    }
  }
  for (const Check& c : checks) {
    auto prepared = reg.prepare(map, scans[c.scan].points, c.request);
    if (!prepared.ok()) continue;
    const double te = now();
    const SearchOutcome ex = exhaustiveSearch(prepared->problem);
    row.exhaustive_ms.push_back((now() - te) * 1e3);
    const SearchOutcome& bb = c.branch_and_bound;
    ++row.compared;
    row.equal += (ex.score == bb.score && ex.heading_index == bb.heading_index && ex.tx == bb.tx &&
                  ex.ty == bb.ty);
  }
}

void printWindows(const std::vector<WindowRow>& rows) {
  std::printf(
      "| window | scans | search points (median) | prepare ms (median) | search ms median / p99 | "
      "filter + search ms median / p99 | "
      "refine / covariance / obstacles ms (median) | match total ms median / p99 | evaluations, %% "
      "of exhaustive (median / max) | table "
      "lookups, millions (median / max) | equal to exhaustive | exhaustive search ms (median) | "
      "success <0.5 m, <1 deg | error after refinement median / p99 | certificate ms (median) "
      "| certified (of them wrong) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const WindowRow& r : rows) {
    std::printf(
        "| %s | %d | %.0f | %.1f | %.1f / %.1f | %.1f / %.1f | %.1f / %.1f / %.1f | %.1f / %.1f | "
        "%.3f / %.3f | "
        "%.1f / %.1f | %d/%d "
        "| %.0f | %d/%d (%.1f%%) | %.3f m, %.3f deg / %.3f m | %.1f | %d/%d (%d) |\n",
        r.name.c_str(), r.runs, median(r.points), median(r.filter_ms), median(r.search_ms),
        percentile(r.search_ms, 99), median(r.filter_search_ms), percentile(r.filter_search_ms, 99),
        median(r.refine_ms), median(r.covariance_ms), median(r.obstacles_ms), median(r.total_ms),
        percentile(r.total_ms, 99), 100 * median(r.fraction), 100 * percentile(r.fraction, 100),
        median(r.lookups) / 1e6, percentile(r.lookups, 100) / 1e6, r.equal, r.compared,
        median(r.exhaustive_ms), r.success, r.runs, 100.0 * r.success / std::max(1, r.runs),
        median(r.error_m), median(r.error_deg), percentile(r.error_m, 99), median(r.certificate_ms),
        r.certified, r.runs, r.certified_wrong);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  o.reg.global.max_evaluations = 0;  // the benchmark measures complete searches (--global-budget)
  if (!parse(argc, argv, o)) {
    usage();
    return 2;
  }
  auto store = MapStore::open(o.map_dir);
  if (!store.ok()) {
    std::fprintf(stderr, "%s\n", store.error().c_str());
    return 1;
  }
  auto scans = loadScans(o.scans_dir, o.count);
  if (!scans.ok()) {
    std::fprintf(stderr, "%s\n", scans.error().c_str());
    return 1;
  }
  std::vector<Eigen::Vector3d> centres;
  size_t raw = 0;
  for (const BenchScan& s : scans.value()) {
    centres.push_back(s.truth.translation());
    raw += s.points.size();
  }
  RasterStats rs;
  auto map = rasterizeAround(store.value(), centres, o.raster_radius_m, o.raster, rs);
  if (!map.ok()) {
    std::fprintf(stderr, "%s\n", map.error().c_str());
    return 1;
  }
  char date[32];
  const std::time_t t = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d", std::localtime(&t));
  std::printf("# Registration benchmark, %s, one thread\n\n", date);
  std::printf("load average at start (1 min, %d cores): %s\n",
              static_cast<int>(std::thread::hardware_concurrency()), loadAverage().c_str());
  std::printf("map %s; %zu test scans from %s, %.0f raw points per scan on average\n",
              o.map_dir.c_str(), scans->size(), o.scans_dir.c_str(),
              static_cast<double>(raw) / scans->size());
  std::printf(
      "rasterized %zu chunks of %d x %d cells in %.2f s (%.1f ms per chunk), %.1f MB (%.2f MB per "
      "chunk)\n\n",
      rs.chunks, o.raster.chunkCells(), o.raster.chunkCells(), rs.seconds,
      1e3 * rs.seconds / std::max<size_t>(1, rs.chunks), rs.bytes / 1e6,
      rs.bytes / 1e6 / std::max<size_t>(1, rs.chunks));

  std::vector<WindowRow> rows(2);
  rows[0].name = "paper: 25 m x 25 m, +-15 deg (offsets within " + std::to_string(int(o.offset_m)) +
                 " m, " + std::to_string(int(o.offset_deg)) + " deg)";
  runWindow(o, map.value(), scans.value(), 12.5, 15.0, o.offset_m, o.offset_deg, rows[0]);
  rows[1].name = "tracking: +-2 m, +-3 deg (offsets within 1.5 m, 2.5 deg)";
  runWindow(o, map.value(), scans.value(), 2.0, 3.0, 1.5, 2.5, rows[1]);
  std::printf("## Search windows\n\n");
  printWindows(rows);

  if (o.global && o.global_count > 0) {
    // Global localization: a prior anywhere in a disc inside the square region, any heading;
    // the search covers the whole square and the full turn. The map is rasterized around the
    // priors, as the map server serves it around a rough fix: the region plus the scan reach.
    std::printf("\n## Global localization (heading-interval branch-and-bound, one thread)\n\n");
    std::printf(
        "| region | loaded map | scans | poses per search (millions) | search ms median / max | "
        "match total ms median / max | evaluations (median) | evaluations x search points, "
        "millions (median) "
        "| success <0.5 m, <1 deg |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    std::vector<BenchScan> first(scans->begin(),
                                 scans->begin() + std::min<size_t>(scans->size(), o.global_count));
    const double largest = *std::max_element(o.global_regions_m.begin(), o.global_regions_m.end());
    for (double edge : o.global_regions_m) {
      const double half = edge / 2;
      for (double extra_m : {0.0, 100.0}) {
        if (extra_m > 0.0 && edge < largest) continue;  // map size only for the largest region
        std::mt19937 rng(o.seed + 7);
        std::vector<Pose6> priors;
        std::vector<Eigen::Vector3d> around;
        for (const BenchScan& s : first) {
          priors.push_back(offsetPrior(s.truth, 0.9 * half, M_PI, rng));
          around.emplace_back(priors.back().x, priors.back().y, 0.0);
        }
        const double radius = half * std::sqrt(2.0) + o.reg.filter.max_range_m + extra_m;
        RasterStats gs;
        auto gmap = rasterizeAround(store.value(), around, radius, o.raster, gs);
        if (!gmap.ok()) {
          std::fprintf(stderr, "%s\n", gmap.error().c_str());
          continue;
        }
        const Registration reg(o.reg);
        std::vector<double> search_ms, total_ms, evals, lookups;
        int ok = 0, runs = 0;
        double poses = 0.0;
        for (size_t i = 0; i < first.size(); ++i) {
          MatchRequest req;
          req.prior = priors[i];
          req.half_x_m = req.half_y_m = half;
          req.half_heading_rad = M_PI;
          ++runs;
          RegistrationTiming timing;
          const double t0 = now();
          auto prepared = reg.prepare(gmap.value(), first[i].points, req);
          if (!prepared.ok()) {
            std::fprintf(stderr, "global scan %d: %s\n", first[i].index, prepared.error().c_str());
            continue;
          }
          const double t1 = now();
          const GlobalSearchOutcome g = globalBranchAndBound(prepared->problem, o.reg.global);
          const double t2 = now();
          search_ms.push_back((t2 - t1) * 1e3);
          evals.push_back(static_cast<double>(g.best.stats.evaluations));
          lookups.push_back(static_cast<double>(g.point_lookups));
          poses = static_cast<double>(g.best.stats.exhaustive_poses);
          std::fprintf(stderr,
                       "global %.0f m scan %d: %s, %.0f ms, %lld evaluations, %lld heading / %lld "
                       "translation splits, %.1f M lookups, queue peak %lld\n",
                       2 * half, first[i].index, g.complete ? "complete" : "budget",
                       (t2 - t1) * 1e3, static_cast<long long>(g.best.stats.evaluations),
                       static_cast<long long>(g.heading_splits),
                       static_cast<long long>(g.translation_splits), g.point_lookups / 1e6,
                       static_cast<long long>(g.best.stats.queue_peak));
          if (!g.complete) {
            total_ms.push_back((now() - t0) * 1e3);
            continue;
          }
          auto r = reg.finish(gmap.value(), first[i].points, req, std::move(prepared.value()),
                              g.best, now, &timing);
          total_ms.push_back((now() - t0) * 1e3);
          if (!r.ok()) {
            std::fprintf(stderr, "global scan %d: %s\n", first[i].index, r.error().c_str());
            continue;
          }
          const Pose6 t = fromIsometry(first[i].truth);
          ok += success(std::hypot(r->pose.x - t.x, r->pose.y - t.y),
                        std::abs(angleDiff(r->pose.yaw, t.yaw)) * 180.0 / M_PI);
        }
        std::printf(
            "| %.0f m x %.0f m x 360 deg | %zu chunks, %.0f MB (radius %.0f m) | %d | %.1f | %.0f "
            "/ %.0f | %.0f / %.0f | %.0f | %.1f | %d/%d |\n",
            2 * half, 2 * half, gs.chunks, gs.bytes / 1e6, radius, runs, poses / 1e6,
            median(search_ms), percentile(search_ms, 100), median(total_ms),
            percentile(total_ms, 100), median(evals), median(lookups) / 1e6, ok, runs);
      }
    }
  }

  if (o.peer_count > 0 && !o.mapping_dir.empty()) {
    std::printf("\n## Peers from the same offsets (within %.0f m, %.0f deg)\n\n", o.offset_m,
                o.offset_deg);
    std::printf("| matcher | scans | success <0.5 m, <1 deg | time per match ms median / p99 |\n");
    std::printf("|---|---|---|---|\n");
    PeerOptions po;
    std::vector<PeerMatcher> peers;
    for (auto kind : {PeerMatcher::Kind::kNdt, PeerMatcher::Kind::kGicp}) {
      PeerMatcher peer(kind, po);
      std::mt19937 rng(o.seed);  // the same offsets as the paper window above
      int ok = 0, n = 0;
      std::vector<double> ms;
      for (size_t i = 0; i < scans->size() && n < o.peer_count; ++i) {
        const BenchScan& s = scans.value()[i];
        const Pose6 prior = offsetPrior(s.truth, o.offset_m, o.offset_deg * M_PI / 180.0, rng);
        auto target = targetCloud(o.mapping_dir, s.truth.translation(), 80.0, 0.5);
        if (!target.ok()) {
          std::fprintf(stderr, "%s\n", target.error().c_str());
          continue;
        }
        peer.setTarget(target.value());
        const PeerResult r = peer.align(s.points, toIsometry(prior));
        const double e = (r.pose.translation() - s.truth.translation()).head<2>().norm();
        const double eh = std::abs(angleDiff(yawOf(r.pose), yawOf(s.truth))) * 180.0 / M_PI;
        ok += success(e, eh);
        ++n;
        ms.push_back(r.seconds * 1e3);
      }
      std::printf("| %s | %d | %d/%d (%.1f%%) | %.0f / %.0f |\n", peer.name().c_str(), n, ok, n,
                  100.0 * ok / std::max(1, n), median(ms), percentile(ms, 99));
    }
    std::printf("| gmm_localization (paper window, above) | %d | %d/%d (%.1f%%) | %.0f / %.0f |\n",
                rows[0].runs, rows[0].success, rows[0].runs,
                100.0 * rows[0].success / std::max(1, rows[0].runs), median(rows[0].total_ms),
                percentile(rows[0].total_ms, 99));
  }

  if (o.sizes) {
    std::printf(
        "\n## Scan size (raw points subsampled evenly, or padded with repeats of the scan's "
        "points)\n\n");
    std::printf(
        "| raw points | paper: prepare / search ms (median) | paper: filter + search ms median "
        "/ p99 | paper: match total ms (median) | tracking: filter + search ms median / p99 | "
        "tracking: match total ms (median) | success paper / tracking |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (size_t size : {20000, 70000, 140000, 280000}) {
      std::vector<BenchScan> sub;
      for (const BenchScan& s : scans.value()) {
        BenchScan c = s;
        if (c.points.size() > size) {
          PointList p;
          const double stride = static_cast<double>(c.points.size()) / size;
          for (size_t k = 0; k < size; ++k) p.push_back(c.points[static_cast<size_t>(k * stride)]);
          c.points = std::move(p);
        } else if (c.points.size() < size) {
          // Pad with repeated points (a denser revolution of the same scene).
          PointList p = c.points;
          for (size_t k = 0; p.size() < size; ++k) p.push_back(c.points[k % c.points.size()]);
          c.points = std::move(p);
        }
        sub.push_back(std::move(c));
      }
      WindowRow paper, tracking;
      Options os = o;
      os.exhaustive_every = 0;
      runWindow(os, map.value(), sub, 12.5, 15.0, o.offset_m, o.offset_deg, paper);
      runWindow(os, map.value(), sub, 2.0, 3.0, 1.5, 2.5, tracking);
      std::printf(
          "| %zu | %.1f / %.1f | %.1f / %.1f | %.1f | %.1f / %.1f | %.1f | %d/%d, %d/%d |\n", size,
          median(paper.filter_ms), median(paper.search_ms), median(paper.filter_search_ms),
          percentile(paper.filter_search_ms, 99), median(paper.total_ms),
          median(tracking.filter_search_ms), percentile(tracking.filter_search_ms, 99),
          median(tracking.total_ms), paper.success, paper.runs, tracking.success, tracking.runs);
    }
  }
  std::printf("\nload average at the end (1 min): %s\n", loadAverage().c_str());
  return 0;
}
