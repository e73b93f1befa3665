// bench_registration: the registration benchmark. Prints markdown tables of search
// time, evaluations and equality with the exhaustive search for the paper's window and a
// tracking window, success and time of PCL NDT and GICP from the same offsets, and time against
// scan size. All numbers come from this run, as ratios where the machine's noise matters.
// Reads KITTI-style folders as build_map does (a KITTI odometry sequence with its calib.txt,
// the simulator's KITTI output, keyframe dumps); --out DIR keeps the run (bench_output.h).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <thread>

#include "bench/bench_data.h"
#include "bench/bench_global_miss.h"
#include "bench/bench_methods.h"
#include "bench/bench_options.h"
#include "bench/bench_output.h"
#include "bench/bench_peers.h"
#include "common/cli_args.h"
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

std::string fmt(const char* format, double a, double b) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

/// The prior's error against the truth, into the record.
void priorError(const Pose6& prior, const Eigen::Isometry3d& truth, ScanRecord& rec) {
  const Pose6 t = fromIsometry(truth);
  rec.offset_m = std::hypot(prior.x - t.x, prior.y - t.y);
  rec.offset_deg = std::abs(angleDiff(prior.yaw, t.yaw)) * 180.0 / M_PI;
}

bool success(double err_m, double err_deg) { return err_m < 0.5 && err_deg < 1.0; }

MatchKey keyOf(const RegistrationResult<MatchResult>& r) {
  MatchKey k;
  if (!r.ok()) {
    k.failure = r.error();
    return k;
  }
  k.heading_index = r->search.heading_index;
  k.tx = r->search.tx;
  k.ty = r->search.ty;
  k.score = r->search.score;
  const Pose6& p = r->pose;
  const double v[6] = {p.x, p.y, p.z, p.roll, p.pitch, p.yaw};
  std::copy(v, v + 6, k.pose);
  k.refined_score = r->refinement.score;
  k.covariance = r->covariance_xyh;
  k.certified = r->certificate.certified;
  k.obstacles = r->obstacles.obstacles;
  return k;
}

/// One registration of scan `s` from `req` by `reg`, timed by stage, into `row` (and one record).
/// Returns the search optimum when the search completed.
/// `method` (null: height on `reg` and `map`) sets the points, request and maps up as its
/// method does; that setting-up is timed with the preparation.
bool matchInto(const Registration& reg, const ChunkMap& map, const BenchScan& s,
               const MatchRequest& request, const std::string& section, WindowRow& row,
               SearchOutcome* optimum, const MethodMatcher* method = nullptr) {
  ++row.runs;
  row.records.emplace_back();
  ScanRecord& rec = row.records.back();
  rec.section = section;
  rec.window = row.name;
  rec.matcher = row.matcher;
  rec.scan = s.index;
  rec.raw_points = static_cast<double>(s.points.size());
  priorError(request.prior, s.truth, rec);
  const double t0 = now();
  MatchRequest req = request;
  PointList own;
  FusedChannel channel;
  const PointList& points = method ? method->input(s, req, own, channel) : s.points;
  const Registration& registration = method ? method->registration : reg;
  const ChunkMap& searched = method ? *method->map : map;
  auto prepared = registration.prepare(searched, points, req);
  if (!prepared.ok()) {
    ++row.failures;
    rec.failure = prepared.error();
    row.results.push_back({});
    row.results.back().failure = prepared.error();
    std::fprintf(stderr, "scan %d: %s\n", s.index, prepared.error().c_str());
    return false;
  }
  const double t1 = now();
  bool complete = true;
  const SearchOutcome bb = registration.search(prepared->problem, nullptr, &complete);
  const double t2 = now();
  if (!complete) {
    ++row.failures;
    rec.failure = "search stopped at its budget";
    row.results.push_back({});
    row.results.back().failure = rec.failure;
    std::fprintf(stderr, "scan %d: search stopped at its budget\n", s.index);
    return false;
  }
  if (optimum != nullptr) *optimum = bb;
  // Search points per heading (fused: the height points and the ground returns).
  const double n =
      static_cast<double>(prepared->problem.points(0).size() + prepared->ground.points.size());
  const double t3 = now();
  RegistrationTiming timing;
  auto r =
      registration.finish(searched, points, req, std::move(prepared.value()), bb, now, &timing);
  const double t4 = now();
  row.results.push_back(keyOf(r));
  row.refine_ms.push_back(timing.refine_s * 1e3);
  if (r.ok()) {
    row.refine_trials.push_back(r->refinement.evaluations);
    row.refine_repeated.push_back(r->refinement.repeated);
  }
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
  rec.search_points = n;
  rec.prepare_ms = row.filter_ms.back();
  rec.search_ms = row.search_ms.back();
  rec.total_ms = row.total_ms.back();
  rec.evaluations_fraction = bb.stats.fraction();
  rec.refine_ms = row.refine_ms.back();
  rec.covariance_ms = row.covariance_ms.back();
  rec.certificate_ms = row.certificate_ms.back();
  rec.obstacles_ms = row.obstacles_ms.back();
  if (!r.ok()) {
    ++row.failures;
    rec.failure = r.error();
    std::fprintf(stderr, "scan %d: %s\n", s.index, r.error().c_str());
    return true;
  }
  const Pose6 t = fromIsometry(s.truth);
  const double e = std::hypot(r->pose.x - t.x, r->pose.y - t.y);
  const double eh = std::abs(angleDiff(r->pose.yaw, t.yaw)) * 180.0 / M_PI;
  row.error_m.push_back(e);
  row.error_deg.push_back(eh);
  row.success += success(e, eh);
  rec.matched = true;
  rec.error_m = e;
  rec.error_deg = eh;
  rec.success = success(e, eh);
  rec.certified = r->certificate.certified ? 1 : 0;
  if (r->certificate.certified) {
    ++row.certified;
    row.certified_wrong += success(e, eh) ? 0 : 1;
  }
  return true;
}

/// Registers every scan from a random offset prior in the window; with `many`, each scan is
/// registered right after again by a registration on `threads` threads (the same request) into
/// `many`, so that the two rows see the same machine state, scan by scan.
/// `methods` (with `matchers`, one each) likewise: each scan by each method from the same request.
void runWindow(const BenchOptions& o, const ChunkMap& map, const std::vector<BenchScan>& scans,
               double half_m, double half_deg, double off_m, double off_deg, WindowRow& row,
               const std::string& section = "window", WindowRow* many = nullptr, int threads = 1,
               std::vector<WindowRow>* methods = nullptr,
               const std::vector<MethodMatcher>* matchers = nullptr) {
  RegistrationOptions ro = o.reg;
  ro.threads = 1;
  const Registration reg(ro);
  ro.threads = threads;
  const Registration reg_many(ro);
  if (many != nullptr) many->threads = reg_many.pool() ? reg_many.pool()->threads() : 1;
  std::mt19937 rng(o.seed);
  // The exhaustive reference runs after the timed pass: seconds of it between matches would
  // flush the caches that a vehicle's consecutive matches share.
  struct Check {
    size_t scan;
    MatchRequest request;
    SearchOutcome branch_and_bound;
    size_t record;
  };
  std::vector<Check> checks;
  for (size_t i = 0; i < scans.size(); ++i) {
    const BenchScan& s = scans[i];
    MatchRequest req;
    req.prior = offsetPrior(s.truth, off_m, off_deg * M_PI / 180.0, rng);
    req.half_x_m = req.half_y_m = half_m;
    req.half_heading_rad = half_deg * M_PI / 180.0;
    SearchOutcome bb;
    const bool searched = matchInto(reg, map, s, req, section, row, &bb);
    if (searched && o.exhaustive_every > 0 && i % o.exhaustive_every == 0) {
      checks.push_back({i, req, bb, row.records.size() - 1});
    }
    if (many != nullptr) matchInto(reg_many, map, s, req, "threads", *many, nullptr);
    for (size_t m = 0; methods != nullptr && m < methods->size(); ++m) {
      matchInto(reg, map, s, req, "methods", (*methods)[m], nullptr, &(*matchers)[m]);
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
    const bool equal = ex.score == bb.score && ex.heading_index == bb.heading_index &&
                       ex.tx == bb.tx && ex.ty == bb.ty;
    row.equal += equal;
    row.records[c.record].equal_to_exhaustive = equal ? 1 : 0;
  }
}

JsonObject windowJson(const WindowRow& r, double half_m, double half_deg, double off_m,
                      double off_deg) {
  JsonObject j;
  j.add("name", r.name)
      .add("half_extent_m", half_m)
      .add("half_heading_deg", half_deg)
      .add("offset_m", off_m)
      .add("offset_deg", off_deg)
      .add("scans", r.runs)
      .add("success", r.success)
      .add("failures", r.failures)
      .add("equal_to_exhaustive", r.equal)
      .add("compared_with_exhaustive", r.compared)
      .add("certified", r.certified)
      .add("certified_wrong", r.certified_wrong)
      .add("search_points_median", median(r.points))
      .add("prepare_ms_median", median(r.filter_ms))
      .add("search_ms_median", median(r.search_ms))
      .add("search_ms_p99", percentile(r.search_ms, 99))
      .add("match_total_ms_median", median(r.total_ms))
      .add("match_total_ms_p99", percentile(r.total_ms, 99))
      .add("evaluations_fraction_median", median(r.fraction))
      .add("evaluations_fraction_max", percentile(r.fraction, 100))
      .add("exhaustive_ms_median", median(r.exhaustive_ms))
      .add("error_m_median", median(r.error_m))
      .add("error_m_p99", percentile(r.error_m, 99))
      .add("error_deg_median", median(r.error_deg))
      .add("certificate_ms_median", median(r.certificate_ms))
      .add("refine_trials_median", median(r.refine_trials))
      .add("refine_repeated_median", median(r.refine_repeated));
  return j;
}

void printWindows(Report& out, const std::vector<WindowRow>& rows) {
  out.print(
      "| window | scans | search points (median) | prepare ms (median) | search ms median / p99 | "
      "filter + search ms median / p99 | "
      "refine / covariance / obstacles ms (median) | match total ms median / p99 | evaluations, %% "
      "of exhaustive (median / max) | table "
      "lookups, millions (median / max) | equal to exhaustive | exhaustive search ms (median) | "
      "success <0.5 m, <1 deg | error after refinement median / p99 | certificate ms (median) "
      "| certified (of them wrong) |\n");
  out.print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const WindowRow& r : rows) {
    out.print(
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
  for (const WindowRow& r : rows) {
    if (r.refine_trials.empty()) continue;
    double trials = 0.0, repeated = 0.0;
    for (size_t i = 0; i < r.refine_trials.size(); ++i) {
      trials += r.refine_trials[i];
      repeated += r.refine_repeated[i];
    }
    out.print(
        "Refinement, %s: %.0f trials per match (median; %.1f mean), %.1f%% of all of them passed "
        "over unscored (a pose the same climb had scored)\n",
        r.name.c_str(), median(r.refine_trials), trials / r.refine_trials.size(),
        100.0 * repeated / std::max(1.0, trials));
  }
}

/// The machine's own ceiling for `threads` threads at this moment: the same fixed piece of
/// arithmetic run `threads` times on one thread and once on each of `threads` threads,
/// median ratio of five tries. On a shared or virtual machine it can be well below the thread
/// count; the match's speed-up is read against it.
double machineCeiling(int threads) {
  auto piece = [] {
    volatile double sink = 0.0;
    double x = 1.0;
    for (int i = 0; i < 4000000; ++i) x = x * 1.0000001 + 1e-9;
    sink = x;
    (void)sink;
  };
  std::vector<double> ratios;
  for (int k = 0; k < 5; ++k) {
    const double t0 = now();
    for (int i = 0; i < threads; ++i) piece();
    const double t1 = now();
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(piece);
    piece();
    for (std::thread& t : pool) t.join();
    const double t2 = now();
    ratios.push_back((t1 - t0) / std::max(1e-9, t2 - t1));
  }
  return median(ratios);
}

/// This machine's memory, measured now: the latency of a dependent random read in a buffer far
/// larger than the caches (a pointer chase over 256 MB) and the bandwidth of a sequential read
/// of it, medians of three tries.
struct MemoryFloor {
  double random_read_ns = 0.0;
  double bandwidth_gb_s = 0.0;
};

MemoryFloor measureMemory() {
  const size_t n = size_t{32} << 20;  // 32 M entries of 8 bytes: 256 MB
  std::vector<uint64_t> next(n);
  // One random cycle through every entry (Sattolo's shuffle), so each read depends on the last.
  for (size_t i = 0; i < n; ++i) next[i] = i;
  std::mt19937_64 rng(5);
  for (size_t i = n - 1; i > 0; --i) std::swap(next[i], next[rng() % i]);
  std::vector<double> lat, bw;
  for (int k = 0; k < 3; ++k) {
    const size_t steps = 4000000;
    uint64_t at = 0;
    const double t0 = now();
    for (size_t i = 0; i < steps; ++i) at = next[at];
    const double t1 = now();
    lat.push_back((t1 - t0) / steps * 1e9 + static_cast<double>(at % 2) * 1e-12);
    uint64_t sum = 0;
    const double t2 = now();
    for (size_t i = 0; i < n; ++i) sum += next[i];
    const double t3 = now();
    bw.push_back(static_cast<double>(n * sizeof(uint64_t)) / (t3 - t2) / 1e9 +
                 static_cast<double>(sum % 2) * 1e-12);
  }
  return {median(lat), median(bw)};
}

/// Each window's search against the memory floor: the table lookups it made at the measured
/// random-read latency (every lookup a miss: an upper bound of what memory costs it), and the
/// cache lines those lookups touch at the measured bandwidth (the bytes-read floor).
void printFloor(Report& out, const std::vector<WindowRow>& rows, const MemoryFloor& m) {
  out.print(
      "\nMemory, measured now: %.1f ns per dependent random read (256 MB pointer chase), %.1f "
      "GB/s sequential read.\n\n",
      m.random_read_ns, m.bandwidth_gb_s);
  out.print(
      "| window | search ms (median) | table lookups (median) | all lookups missing the caches, "
      "ms | their 64-byte lines at the bandwidth, ms | search time per lookup, ns |\n");
  out.print("|---|---|---|---|---|---|\n");
  for (const WindowRow& r : rows) {
    const double lookups = median(r.lookups);
    out.print("| %s | %.1f | %.2f M | %.1f | %.1f | %.1f |\n", r.name.c_str(), median(r.search_ms),
              lookups / 1e6, lookups * m.random_read_ns * 1e-6,
              lookups * 64.0 / (m.bandwidth_gb_s * 1e9) * 1e3,
              median(r.search_ms) * 1e6 / std::max(1.0, lookups));
  }
}

/// Median of the per-scan ratios a / b (scans where both ran).
double medianRatio(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (b[i] > 0.0) r.push_back(a[i] / b[i]);
  }
  return median(r);
}

/// The same windows on one and on N threads: each stage's median time on both, the whole
/// match's speed-up, and how many results are identical bit for bit (pose, search optimum,
/// refined score, covariance, certificate, obstacle count).
JsonObject printThreads(Report& out, const WindowRow& one, const WindowRow& many) {
  const int n = many.threads;
  int identical = 0, compared = 0;
  for (size_t i = 0; i < std::min(one.results.size(), many.results.size()); ++i) {
    ++compared;
    identical += one.results[i] == many.results[i] ? 1 : 0;
  }
  auto pair = [&](const std::vector<double>& a, const std::vector<double>& b) {
    return fmt("%.1f / %.1f", median(a), median(b));
  };
  const double speedup_median = median(one.total_ms) / std::max(1e-9, median(many.total_ms));
  const double speedup_p99 =
      percentile(one.total_ms, 99) / std::max(1e-9, percentile(many.total_ms, 99));
  out.print(
      "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %.2fx / %.2fx / %.2fx | %d/%d |\n",
      one.name.c_str(), pair(one.filter_ms, many.filter_ms).c_str(),
      pair(one.search_ms, many.search_ms).c_str(), pair(one.refine_ms, many.refine_ms).c_str(),
      pair(one.covariance_ms, many.covariance_ms).c_str(),
      pair(one.certificate_ms, many.certificate_ms).c_str(),
      pair(one.obstacles_ms, many.obstacles_ms).c_str(), pair(one.total_ms, many.total_ms).c_str(),
      fmt("%.1f / %.1f", percentile(one.total_ms, 99), percentile(many.total_ms, 99)).c_str(),
      speedup_median, speedup_p99, medianRatio(one.total_ms, many.total_ms), identical, compared);
  JsonObject j;
  j.add("name", one.name)
      .add("threads", n)
      .add("match_total_ms_median_1", median(one.total_ms))
      .add("match_total_ms_median_n", median(many.total_ms))
      .add("match_total_ms_p99_1", percentile(one.total_ms, 99))
      .add("match_total_ms_p99_n", percentile(many.total_ms, 99))
      .add("speedup_median", speedup_median)
      .add("speedup_p99", speedup_p99)
      .add("speedup_per_scan_median", medianRatio(one.total_ms, many.total_ms))
      .add("search_ms_median_1", median(one.search_ms))
      .add("search_ms_median_n", median(many.search_ms))
      .add("identical_results", identical)
      .add("compared", compared);
  return j;
}

/// The data set's summary lines: poses, scans, skipped poses, layout, calibration.
void printData(Report& out, const char* what, const KittiInput& in, const KittiScans& d) {
  out.print("%s %s: %zu poses in %s, %zu with a scan file", what, in.dir.c_str(), d.poses,
            d.source.poses_file.c_str(), d.scans.size());
  if (!d.missing.empty()) {
    out.print(", %zu skipped (no scan file; first: %d)", d.missing.size(), d.missing.front());
  }
  out.print("; %s%s\n", d.layout.c_str(),
            in.calib_file.empty() ? "; poses are the sensor's"
                                  : ("; KITTI calibration " + in.calib_file +
                                     " (poses: camera 0; map frame: first Velodyne frame)")
                                        .c_str());
  if (d.ambiguous)
    std::fprintf(stderr, "warning: %s %s: %s\n", what, in.dir.c_str(), d.layout.c_str());
}

JsonObject dataJson(const KittiInput& in, const KittiScans& d) {
  JsonObject j;
  j.add("dir", in.dir)
      .add("poses_file", d.source.poses_file)
      .add("kitti_calib", in.calib_file)
      .add("point_format", pointFormatName(d.source.fields))
      .add("layout", d.layout)
      .add("layout_ambiguous", d.ambiguous)
      .add("poses", d.poses)
      .add("scans_with_file", d.scans.size())
      .add("skipped_without_file", d.missing.size())
      .add("skipped", d.missing);
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions o;
  o.reg.global.max_evaluations = 0;  // the benchmark measures complete searches (--global-budget)
  bool help = false;
  gmm_localization::tools::NormalizedArgs args(argc, argv);
  if (!parseBenchOptions(args.argc(), args.argv(), o, help)) {
    std::fputs(benchUsage(), help ? stdout : stderr);
    return help ? 0 : 2;
  }
  if (!o.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.out_dir, ec);
    if (ec) {
      std::fprintf(stderr, "--out %s: %s\n", o.out_dir.c_str(), ec.message().c_str());
      return 1;
    }
  }
  if (o.track_offset_m > 2.0 || o.track_offset_deg > 3.0) {
    std::fprintf(stderr,
                 "warning: tracking offsets %.2f m / %.2f deg reach beyond the +-2 m, +-3 deg "
                 "window: some truths lie outside it\n",
                 o.track_offset_m, o.track_offset_deg);
  }
  auto store = MapStore::open(o.map_dir);
  if (!store.ok()) {
    std::fprintf(stderr, "%s\n", store.error().c_str());
    return 1;
  }
  // The other methods' layer, checked before anything is read (a missing one names build_map).
  const bool layer_needed = needsReflectivityLayer(o.methods);
  Result<MapStore> layer_store = Result<MapStore>::failure("not needed");
  if (layer_needed) {
    layer_store = openReflectivityLayer(o.map_dir);
    if (!layer_store.ok()) {
      std::fprintf(stderr, "%s\n", layer_store.error().c_str());
      return 1;
    }
  }
  KittiScans data;
  auto scans = loadScans(o.scans, o.count, &data);
  if (!scans.ok()) {
    std::fprintf(stderr, "%s\n", scans.error().c_str());
    return 1;
  }
  if (layer_needed && scans->front().intensity.size() != scans->front().points.size()) {
    std::fprintf(stderr,
                 "--methods reflectivity / fused need each point's intensity: %s (--point-format "
                 "xyzi, if the records hold it)\n",
                 data.layout.c_str());
    return 1;
  }
  KittiScans mapping;
  const bool with_peers = o.peer_count > 0 && !o.mapping.dir.empty();
  if (with_peers) {
    auto m = openKittiInput(o.mapping);
    if (!m.ok()) {
      std::fprintf(stderr, "--mapping: %s\n", m.error().c_str());
      return 1;
    }
    mapping = std::move(m.value());
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
  RasterStats layer_stats;
  Result<ChunkMap> layer_map = Result<ChunkMap>::failure("not needed");
  std::vector<MethodMatcher> matchers;
  if (layer_needed) {
    layer_map =
        rasterizeAround(layer_store.value(), centres, o.raster_radius_m, o.raster, layer_stats);
    if (!layer_map.ok()) {
      std::fprintf(stderr, "%s/reflectivity: %s\n", o.map_dir.c_str(), layer_map.error().c_str());
      return 1;
    }
    const std::string incompatible = channelCompatibility(map.value(), layer_map.value());
    const bool fused =
        std::find(o.methods.begin(), o.methods.end(), MatchMethod::kFused) != o.methods.end();
    if (fused && !incompatible.empty()) {
      std::fprintf(stderr, "--methods fused: %s and its reflectivity layer differ: %s\n",
                   o.map_dir.c_str(), incompatible.c_str());
      return 1;
    }
    for (size_t m = 1; m < o.methods.size(); ++m) {
      matchers.emplace_back(o.methods[m], o.reg, map.value(), &layer_map.value(),
                            layer_store->reflectivity());
    }
  }
  Report out;
  std::vector<ScanRecord> records;
  JsonObject summary;
  char date[32];
  const std::time_t t = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d", std::localtime(&t));
  const std::string load_start = loadAverage();
  out.print("# Registration benchmark, %s, one thread%s\n\n", date,
            o.threads != 1 ? " (and the threads table)" : "");
  out.print("load average at start (1 min, %d cores): %s\n",
            static_cast<int>(std::thread::hardware_concurrency()), load_start.c_str());
  printData(out, "test scans", o.scans, data);
  if (with_peers) printData(out, "mapping scans", o.mapping, mapping);
  out.print("map %s; %zu test scans from %s, %.0f raw points per scan on average\n",
            o.map_dir.c_str(), scans->size(), o.scans.dir.c_str(),
            static_cast<double>(raw) / scans->size());
  out.print(
      "rasterized %zu chunks of %d x %d cells in %.2f s (%.1f ms per chunk), %.1f MB (%.2f MB per "
      "chunk)\n\n",
      rs.chunks, o.raster.chunkCells(), o.raster.chunkCells(), rs.seconds,
      1e3 * rs.seconds / std::max<size_t>(1, rs.chunks), rs.bytes / 1e6,
      rs.bytes / 1e6 / std::max<size_t>(1, rs.chunks));
  std::string command;
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(argv[i]);
  summary.add("date", date)
      .add("command", command)
      .add("load_average_start", load_start)
      .add("map", o.map_dir)
      .add("test_scans", dataJson(o.scans, data))
      .add("seed", static_cast<long long>(o.seed))
      .add("heading_step_deg", o.reg.heading_step_rad * 180.0 / M_PI);
  if (with_peers) summary.add("mapping_scans", dataJson(o.mapping, mapping));

  std::vector<WindowRow> rows(2), many(2);
  WindowRow* many0 = o.threads != 1 ? &many[0] : nullptr;
  WindowRow* many1 = o.threads != 1 ? &many[1] : nullptr;
  rows[0].name = many[0].name =
      fmt("paper: 25 m x 25 m, +-15 deg (offsets within %g m, %g deg)", o.offset_m, o.offset_deg);
  rows[1].name = many[1].name = fmt("tracking: +-2 m, +-3 deg (offsets within %g m, %g deg)",
                                    o.track_offset_m, o.track_offset_deg);
  // Per window: the other methods' rows (the height row is rows[w]).
  std::vector<std::vector<WindowRow>> method_rows(2);
  for (size_t w = 0; w < 2; ++w) {
    for (const MethodMatcher& m : matchers) {
      method_rows[w].emplace_back();
      method_rows[w].back().name = rows[w].name;
      method_rows[w].back().method = m.method;
      method_rows[w].back().matcher = std::string("gmm_localization ") + matchMethodName(m.method);
    }
  }
  runWindow(o, map.value(), scans.value(), 12.5, 15.0, o.offset_m, o.offset_deg, rows[0], "window",
            many0, o.threads, &method_rows[0], &matchers);
  runWindow(o, map.value(), scans.value(), 2.0, 3.0, o.track_offset_m, o.track_offset_deg, rows[1],
            "window", many1, o.threads, &method_rows[1], &matchers);
  out.print("## Search windows\n\n");
  out.print(
      "Offsets: paper window within %g m, +-%g deg (--offset-m, --offset-deg); tracking window "
      "within %g m, +-%g deg (--track-offset-m, --track-offset-deg).\n\n",
      o.offset_m, o.offset_deg, o.track_offset_m, o.track_offset_deg);
  printWindows(out, rows);
  if (o.memory_floor) {
    const MemoryFloor floor = measureMemory();
    printFloor(out, rows, floor);
    summary.add("random_read_ns", floor.random_read_ns).add("bandwidth_gb_s", floor.bandwidth_gb_s);
  }
  summary.add("windows", std::vector<JsonObject>{
                             windowJson(rows[0], 12.5, 15.0, o.offset_m, o.offset_deg),
                             windowJson(rows[1], 2.0, 3.0, o.track_offset_m, o.track_offset_deg)});
  for (const WindowRow& r : rows) records.insert(records.end(), r.records.begin(), r.records.end());
  if (!matchers.empty()) {
    out.print("\n## Match methods (--methods)\n\n");
    out.print("reflectivity layer %s/reflectivity: %s; rasterized %zu chunks in %.2f s\n\n",
              o.map_dir.c_str(), describeReflectivityLayer(layer_store->reflectivity()).c_str(),
              layer_stats.chunks, layer_stats.seconds);
    std::vector<std::vector<WindowRow>> table(2);
    for (size_t w = 0; w < 2; ++w) {
      table[w].push_back(rows[w]);
      for (const WindowRow& r : method_rows[w]) {
        table[w].push_back(r);
        records.insert(records.end(), r.records.begin(), r.records.end());
      }
    }
    summary.add("methods", printMethods(out, table));
  }

  if (o.threads != 1) {
    // The same scans and priors with the match on N threads, each scan right after its
    // one-thread match (runWindow): the ratios come from one run, scan by scan.
    const double ceiling = machineCeiling(many[0].threads);
    out.print("\n## Threads: the whole match on 1 and %d threads (load average now %s)\n\n",
              many[0].threads, loadAverage().c_str());
    out.print(
        "This machine's own ceiling now: %.2fx (a fixed piece of arithmetic on 1 and on %d "
        "threads, median of five; a shared or virtual machine gives less than the thread "
        "count).\n\n",
        ceiling, many[0].threads);
    summary.add("machine_ceiling", ceiling);
    out.print(
        "Each cell: median ms on 1 / %d threads. Speed-up of the whole match: ratio of the "
        "medians / of the p99s / median of the per-scan ratios. Identical: the same pose, search "
        "optimum, refined score, covariance, certificate and obstacle count, bit for bit.\n\n",
        many[0].threads);
    out.print(
        "| window | prepare | search | refine | covariance | certificate | obstacles | match total "
        "(median) | match total (p99) | speed-up | identical |\n");
    out.print("|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<JsonObject> threads_json;
    for (size_t w = 0; w < rows.size(); ++w) {
      threads_json.push_back(printThreads(out, rows[w], many[w]));
    }
    summary.add("threads", threads_json);
  }

  std::vector<JsonObject> global_json;
  if (o.global && o.global_count > 0) {
    // Global localization: a prior anywhere in a disc inside the square region, any heading;
    // the search covers the whole square and the full turn. The map is rasterized around the
    // priors, as the map server serves it around a rough fix: the region plus the scan reach.
    out.print("\n## Global localization (heading-interval branch-and-bound, %d thread%s)\n\n",
              o.global_threads, o.global_threads == 1 ? "" : "s");
    std::shared_ptr<TaskPool> global_pool;
    if (o.global_threads > 1) global_pool = std::make_shared<TaskPool>(o.global_threads);
    out.print(
        "| region | loaded map | scans | poses per search (millions) | search ms median / max | "
        "match total ms median / max | evaluations (median) | evaluations x search points, "
        "millions (median) "
        "| success <0.5 m, <1 deg | certified, both proofs (of them wrong) | optimum nats/pt "
        "(lowest) |\n");
    out.print("|---|---|---|---|---|---|---|---|---|---|---|\n");
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
        const std::string name = fmt("%.0f m x %.0f m x 360 deg", 2 * half, 2 * half) +
                                 (extra_m > 0.0 ? " (map radius +100 m)" : "");
        const Registration reg(o.reg, global_pool);  // the rest of the match on the same threads
        std::vector<double> search_ms, total_ms, evals, lookups, optimum_per_point;
        int ok = 0, runs = 0, certified = 0, certified_wrong = 0;
        double poses = 0.0;
        for (size_t i = 0; i < first.size(); ++i) {
          MatchRequest req;
          req.prior = priors[i];
          req.half_x_m = req.half_y_m = half;
          req.half_heading_rad = M_PI;
          ++runs;
          ScanRecord rec;
          rec.section = "global";
          rec.window = name;
          rec.scan = first[i].index;
          rec.raw_points = static_cast<double>(first[i].points.size());
          priorError(req.prior, first[i].truth, rec);
          RegistrationTiming timing;
          const double t0 = now();
          auto prepared = reg.prepare(gmap.value(), first[i].points, req);
          if (!prepared.ok()) {
            std::fprintf(stderr, "global scan %d: %s\n", first[i].index, prepared.error().c_str());
            rec.failure = prepared.error();
            records.push_back(rec);
            continue;
          }
          const double t1 = now();
          const GlobalSearchOutcome g =
              globalBranchAndBound(prepared->problem, o.reg.global, global_pool.get());
          const double t2 = now();
          search_ms.push_back((t2 - t1) * 1e3);
          evals.push_back(static_cast<double>(g.best.stats.evaluations));
          if (g.complete) {
            optimum_per_point.push_back(g.best.log_likelihood /
                                        static_cast<double>(prepared->problem.scanPoints()));
          }
          lookups.push_back(static_cast<double>(g.point_lookups));
          poses = static_cast<double>(g.best.stats.exhaustive_poses);
          rec.prepare_ms = (t1 - t0) * 1e3;
          rec.search_ms = (t2 - t1) * 1e3;
          std::fprintf(stderr,
                       "global %.0f m scan %d: %s, %.0f ms, %lld evaluations, %lld heading / %lld "
                       "translation splits, %.1f M lookups, queue peak %lld\n",
                       2 * half, first[i].index,
                       g.complete ? "complete" : (g.below_floor ? "below the floor" : "budget"),
                       (t2 - t1) * 1e3, static_cast<long long>(g.best.stats.evaluations),
                       static_cast<long long>(g.heading_splits),
                       static_cast<long long>(g.translation_splits), g.point_lookups / 1e6,
                       static_cast<long long>(g.best.stats.queue_peak));
          if (!g.complete) {
            total_ms.push_back((now() - t0) * 1e3);
            rec.total_ms = total_ms.back();
            rec.failure = g.below_floor ? "no pose reaches the global search's score floor"
                                        : "global search stopped at its budget";
            records.push_back(rec);
            continue;
          }
          auto r = reg.finish(gmap.value(), first[i].points, req, std::move(prepared.value()),
                              g.best, now, &timing);
          total_ms.push_back((now() - t0) * 1e3);
          rec.total_ms = total_ms.back();
          if (!r.ok()) {
            std::fprintf(stderr, "global scan %d: %s\n", first[i].index, r.error().c_str());
            rec.failure = r.error();
            records.push_back(rec);
            continue;
          }
          const Pose6 t = fromIsometry(first[i].truth);
          rec.matched = true;
          rec.error_m = std::hypot(r->pose.x - t.x, r->pose.y - t.y);
          rec.error_deg = std::abs(angleDiff(r->pose.yaw, t.yaw)) * 180.0 / M_PI;
          rec.success = success(rec.error_m, rec.error_deg);
          rec.certified = r->certificate.certified ? 1 : 0;
          certified += rec.certified;
          certified_wrong += rec.certified && !rec.success;
          std::fprintf(stderr,
                       "global %.0f m scan %d: error %.2f m %.2f deg, %s (global proof %s, %lld "
                       "evaluations, separation %.3f/pt), %.0f ms after the search\n",
                       2 * half, first[i].index, rec.error_m, rec.error_deg,
                       r->certificate.certified ? "certified"
                                                : certificateFailureName(r->certificate.failure),
                       r->global_certificate.certified
                           ? "held"
                           : certificateFailureName(r->global_certificate.failure),
                       static_cast<long long>(r->global_certificate.evaluations),
                       r->global_certificate.separation_per_point, (now() - t2) * 1e3);
          ok += rec.success;
          records.push_back(rec);
        }
        out.print(
            "| %.0f m x %.0f m x 360 deg | %zu chunks, %.0f MB (radius %.0f m) | %d | %.1f | %.0f "
            "/ %.0f | %.0f / %.0f | %.0f | %.1f | %d/%d | %d/%d (%d) | %.2f |\n",
            2 * half, 2 * half, gs.chunks, gs.bytes / 1e6, radius, runs, poses / 1e6,
            median(search_ms), percentile(search_ms, 100), median(total_ms),
            percentile(total_ms, 100), median(evals), median(lookups) / 1e6, ok, runs, certified,
            runs, certified_wrong, percentile(optimum_per_point, 0));
        JsonObject g;
        g.add("name", name)
            .add("region_m", 2 * half)
            .add("map_radius_m", radius)
            .add("chunks", gs.chunks)
            .add("scans", runs)
            .add("success", ok)
            .add("certified", certified)
            .add("certified_wrong", certified_wrong)
            .add("search_ms_median", median(search_ms))
            .add("search_ms_max", percentile(search_ms, 100))
            .add("match_total_ms_median", median(total_ms))
            .add("evaluations_median", median(evals))
            .add("optimum_per_point_lowest", percentile(optimum_per_point, 0));
        global_json.push_back(g);
      }
    }
    summary.add("global", global_json);
    summary.add("global_miss",
                benchGlobalMiss(out, store.value(), first, o, global_pool, &records));
  }

  if (with_peers) {
    // From the paper window's offsets (10 m) and from the tracking window's (1.5 m): what a user
    // gives up or gains against the matchers they know, at both distances.
    out.print("\n## Peers from the same offsets as our windows\n\n");
    out.print(
        "Target clouds: %s (--peer-target-stride, --peer-target-exclude, "
        "--peer-target-radius).\n\n",
        describe(o.peer_target).c_str());
    out.print(
        "| matcher | offsets | scans | success <0.5 m, <1 deg | time per match ms median / p99 "
        "|\n");
    out.print("|---|---|---|---|---|\n");
    PeerOptions po;
    std::vector<JsonObject> peer_json;
    struct Offsets {
      double m, deg;
      const WindowRow& ours;
      const char* window;
    };
    for (const Offsets& off :
         {Offsets{o.offset_m, o.offset_deg, rows[0], "paper window"},
          Offsets{o.track_offset_m, o.track_offset_deg, rows[1], "tracking window"}}) {
      const std::string offsets = fmt("within %g m, %g deg", off.m, off.deg);
      for (auto kind : {PeerMatcher::Kind::kNdt, PeerMatcher::Kind::kGicp}) {
        PeerMatcher peer(kind, po);
        std::mt19937 rng(o.seed);  // the same offsets as our window's
        int ok = 0, n = 0;
        std::vector<double> ms;
        for (size_t i = 0; i < scans->size() && n < o.peer_count; ++i) {
          const BenchScan& s = scans.value()[i];
          const Pose6 prior = offsetPrior(s.truth, off.m, off.deg * M_PI / 180.0, rng);
          auto target = targetCloud(mapping, s.truth.translation(), s.index, o.peer_target);
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
          ScanRecord rec;
          rec.section = "peers";
          rec.window = off.ours.name;
          rec.matcher = peer.name();
          rec.scan = s.index;
          rec.raw_points = static_cast<double>(s.points.size());
          priorError(prior, s.truth, rec);
          rec.matched = r.pose.matrix().allFinite();
          rec.error_m = e;
          rec.error_deg = eh;
          rec.success = success(e, eh);
          rec.total_ms = r.seconds * 1e3;
          if (!r.converged) rec.failure = "not converged";
          records.push_back(rec);
        }
        out.print("| %s | %s | %d | %d/%d (%.1f%%) | %.0f / %.0f |\n", peer.name().c_str(),
                  offsets.c_str(), n, ok, n, 100.0 * ok / std::max(1, n), median(ms),
                  percentile(ms, 99));
        JsonObject p;
        p.add("matcher", peer.name())
            .add("offset_m", off.m)
            .add("offset_deg", off.deg)
            .add("scans", n)
            .add("success", ok)
            .add("ms_median", median(ms))
            .add("ms_p99", percentile(ms, 99));
        peer_json.push_back(p);
      }
      const WindowRow& r = off.ours;
      out.print("| gmm_localization (%s, above) | %s | %d | %d/%d (%.1f%%) | %.0f / %.0f |\n",
                off.window, offsets.c_str(), r.runs, r.success, r.runs,
                100.0 * r.success / std::max(1, r.runs), median(r.total_ms),
                percentile(r.total_ms, 99));
    }
    summary.add("peer_target", describe(o.peer_target)).add("peers", peer_json);
  }

  if (o.sizes) {
    out.print(
        "\n## Scan size (raw points subsampled evenly, or padded with repeats of the scan's "
        "points)\n\n");
    out.print(
        "| raw points | paper: prepare / search ms (median) | paper: filter + search ms median "
        "/ p99 | paper: match total ms (median) | tracking: filter + search ms median / p99 | "
        "tracking: match total ms (median) | success paper / tracking |\n");
    out.print("|---|---|---|---|---|---|---|\n");
    std::vector<JsonObject> size_json;
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
      paper.name = rows[0].name;
      tracking.name = rows[1].name;
      BenchOptions os = o;
      os.exhaustive_every = 0;
      const std::string section = "scan size " + std::to_string(size);
      runWindow(os, map.value(), sub, 12.5, 15.0, o.offset_m, o.offset_deg, paper, section);
      runWindow(os, map.value(), sub, 2.0, 3.0, o.track_offset_m, o.track_offset_deg, tracking,
                section);
      out.print("| %zu | %.1f / %.1f | %.1f / %.1f | %.1f | %.1f / %.1f | %.1f | %d/%d, %d/%d |\n",
                size, median(paper.filter_ms), median(paper.search_ms),
                median(paper.filter_search_ms), percentile(paper.filter_search_ms, 99),
                median(paper.total_ms), median(tracking.filter_search_ms),
                percentile(tracking.filter_search_ms, 99), median(tracking.total_ms), paper.success,
                paper.runs, tracking.success, tracking.runs);
      for (const WindowRow* r : {&paper, &tracking}) {
        records.insert(records.end(), r->records.begin(), r->records.end());
      }
      JsonObject j;
      j.add("raw_points", size)
          .add("paper", windowJson(paper, 12.5, 15.0, o.offset_m, o.offset_deg))
          .add("tracking", windowJson(tracking, 2.0, 3.0, o.track_offset_m, o.track_offset_deg));
      size_json.push_back(j);
    }
    summary.add("scan_sizes", size_json);
  }
  const std::string load_end = loadAverage();
  out.print("\nload average at the end (1 min): %s\n", load_end.c_str());
  summary.add("load_average_end", load_end);
  if (!o.out_dir.empty()) {
    const std::string csv = o.out_dir + "/scans.csv", md = o.out_dir + "/summary.md",
                      json = o.out_dir + "/summary.json";
    if (!writeScanCsv(records, csv) || !writeTextFile(md, out.text()) ||
        !writeTextFile(json, summary.text())) {
      std::fprintf(stderr, "cannot write the run's files in %s\n", o.out_dir.c_str());
      return 1;
    }
    std::fprintf(stderr, "wrote %s (%zu rows), %s and %s\n", csv.c_str(), records.size(),
                 md.c_str(), json.c_str());
  }
  return 0;
}
