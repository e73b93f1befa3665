#include "bench/bench_methods.h"

#include <algorithm>
#include <cmath>

#include "gmm_localization/core/matching/reflectivity_scan.h"

namespace gmm_localization {
namespace bench {

bool MatchKey::operator==(const MatchKey& o) const {
  return failure == o.failure && heading_index == o.heading_index && tx == o.tx && ty == o.ty &&
         score == o.score && std::equal(pose, pose + 6, o.pose) &&
         refined_score == o.refined_score && covariance == o.covariance &&
         certified == o.certified && obstacles == o.obstacles;
}

bool parseMethodList(const std::string& text, std::vector<MatchMethod>* out) {
  std::vector<MatchMethod> methods = {MatchMethod::kHeight};
  if (text == "all") {
    methods = {MatchMethod::kHeight, MatchMethod::kReflectivity, MatchMethod::kFused};
  } else {
    size_t start = 0;
    while (true) {
      const size_t comma = text.find(',', start);
      const std::string name = text.substr(start, comma - start);
      MatchMethod m;
      if (!parseMatchMethod(name, &m)) return false;
      if (std::find(methods.begin(), methods.end(), m) == methods.end()) methods.push_back(m);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  *out = methods;
  return true;
}

bool needsReflectivityLayer(const std::vector<MatchMethod>& methods) {
  return std::any_of(methods.begin(), methods.end(),
                     [](MatchMethod m) { return m != MatchMethod::kHeight; });
}

Result<MapStore> openReflectivityLayer(const std::string& map_dir) {
  const std::string dir = map_dir + "/reflectivity";
  const std::string how =
      "; build it with: build_map --kitti MAPPING_DIR --kitti-fields xyzi "
      "--layer reflectivity --output " +
      dir + " (the scans the height map was built from)";
  auto store = MapStore::open(dir);
  if (!store.ok()) {
    return Result<MapStore>::failure(
        "--methods reflectivity / fused need the map's reflectivity layer in " + dir + ": " +
        store.error() + how);
  }
  if (store->layer() != MapLayer::kReflectivity) {
    return Result<MapStore>::failure("--methods reflectivity / fused: " + dir + " holds a " +
                                     mapLayerName(store->layer()) +
                                     " map, not the reflectivity layer" + how);
  }
  return store;
}

MethodMatcher::MethodMatcher(MatchMethod m, const RegistrationOptions& height_options,
                             const ChunkMap& height_map, const ChunkMap* reflectivity,
                             const ReflectivityLayerOptions& definition)
    : method(m),
      registration(m == MatchMethod::kReflectivity ? reflectivityRegistrationOptions(height_options)
                                                   : height_options),
      map(m == MatchMethod::kReflectivity ? reflectivity : &height_map),
      reflectivity_map(reflectivity),
      layer(definition) {}

const PointList& MethodMatcher::input(const BenchScan& scan, MatchRequest& req, PointList& own,
                                      FusedChannel& channel) const {
  if (method == MatchMethod::kHeight) return scan.points;
  own = reflectivityPoints(scan.points, scan.intensity, req.prior.roll, req.prior.pitch, layer);
  if (method == MatchMethod::kReflectivity) {
    req.prior.z = req.prior.roll = req.prior.pitch = 0.0;
    return own;
  }
  channel.map = reflectivity_map;
  channel.points = std::move(own);
  req.fused = &channel;
  return scan.points;
}

namespace {

/// Median of the per-registration ratios a / b of the whole match, over the registrations
/// where both matched (records in run order: the same scan and prior at the same index).
double perScanRatio(const WindowRow& a, const WindowRow& b) {
  std::vector<double> r;
  for (size_t i = 0; i < std::min(a.records.size(), b.records.size()); ++i) {
    const ScanRecord& x = a.records[i];
    const ScanRecord& y = b.records[i];
    if (x.matched && y.matched && x.total_ms > 0.0 && y.total_ms > 0.0) {
      r.push_back(x.total_ms / y.total_ms);
    }
  }
  return median(r);
}

double ratioOfMedians(const std::vector<double>& a, const std::vector<double>& b) {
  const double d = median(b);
  return d > 0.0 ? median(a) / d : NAN;
}

}  // namespace

std::vector<JsonObject> printMethods(Report& out,
                                     const std::vector<std::vector<WindowRow>>& windows) {
  out.print(
      "Each method on the same scans from the same priors, scan by scan right after the height "
      "match (the height rows are the window table's). Search points: the height points; "
      "fused: height points + ground returns; reflectivity: ground returns. Ratios to height: "
      "of the medians (search, refinement, whole match) and the median of the per-scan ratios "
      "of the whole match.\n\n");
  out.print(
      "| window | method | scans | search points (median) | prepare ms (median) | search ms "
      "median / p99 | refine ms (median) | match total ms median / p99 | success <0.5 m, <1 deg "
      "| error median m, deg / p99 m | certified (of them wrong) | x height: search / refine / "
      "match total | x height: match total per scan (median) |\n");
  out.print("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<JsonObject> json;
  for (const std::vector<WindowRow>& rows : windows) {
    if (rows.empty()) continue;
    const WindowRow& height = rows.front();
    const std::string window = height.name.substr(0, height.name.find(':'));
    for (const WindowRow& r : rows) {
      const double rs = ratioOfMedians(r.search_ms, height.search_ms);
      const double rr = ratioOfMedians(r.refine_ms, height.refine_ms);
      const double rt = ratioOfMedians(r.total_ms, height.total_ms);
      const double per_scan = perScanRatio(r, height);
      out.print(
          "| %s | %s | %d | %.0f | %.1f | %.1f / %.1f | %.1f | %.1f / %.1f | %d/%d (%.1f%%) | "
          "%.3f, %.3f / %.3f | %d/%d (%d) | %.2f / %.2f / %.2f | %.2f |\n",
          window.c_str(), matchMethodName(r.method), r.runs, median(r.points), median(r.filter_ms),
          median(r.search_ms), percentile(r.search_ms, 99), median(r.refine_ms), median(r.total_ms),
          percentile(r.total_ms, 99), r.success, r.runs, 100.0 * r.success / std::max(1, r.runs),
          median(r.error_m), median(r.error_deg), percentile(r.error_m, 99), r.certified, r.runs,
          r.certified_wrong, rs, rr, rt, per_scan);
      JsonObject j;
      j.add("window", height.name)
          .add("method", matchMethodName(r.method))
          .add("scans", r.runs)
          .add("success", r.success)
          .add("failures", r.failures)
          .add("certified", r.certified)
          .add("certified_wrong", r.certified_wrong)
          .add("search_points_median", median(r.points))
          .add("prepare_ms_median", median(r.filter_ms))
          .add("search_ms_median", median(r.search_ms))
          .add("search_ms_p99", percentile(r.search_ms, 99))
          .add("refine_ms_median", median(r.refine_ms))
          .add("match_total_ms_median", median(r.total_ms))
          .add("match_total_ms_p99", percentile(r.total_ms, 99))
          .add("error_m_median", median(r.error_m))
          .add("error_m_p99", percentile(r.error_m, 99))
          .add("error_deg_median", median(r.error_deg))
          .add("ratio_to_height_search", rs)
          .add("ratio_to_height_refine", rr)
          .add("ratio_to_height_match_total", rt)
          .add("ratio_to_height_match_total_per_scan_median", per_scan);
      json.push_back(j);
    }
  }
  return json;
}

}  // namespace bench
}  // namespace gmm_localization
