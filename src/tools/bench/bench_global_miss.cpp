#include "bench/bench_global_miss.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/global_search.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace bench {
namespace {

double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string twoDecimals(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

/// How the searches of one row ended.
struct MissRow {
  int scans = 0, below_floor = 0, budget = 0, found = 0;
  double best_found_per_point = -std::numeric_limits<double>::infinity();
  std::vector<double> search_ms, evaluations;
};

}  // namespace

std::vector<JsonObject> benchGlobalMiss(Report& out, const MapStore& store,
                                        const std::vector<BenchScan>& scans, const BenchOptions& o,
                                        const std::shared_ptr<TaskPool>& pool,
                                        std::vector<ScanRecord>* records) {
  std::vector<JsonObject> rows_json;
  if (scans.empty() || o.global_regions_m.empty()) return rows_json;
  const double edge = *std::max_element(o.global_regions_m.begin(), o.global_regions_m.end());
  const double half = edge / 2;
  const int64_t budget = o.reg.global.max_evaluations > 0 ? o.reg.global.max_evaluations
                                                          : GlobalSearchOptions().max_evaluations;
  // Priors `edge` from the truth: the vehicle lies outside the square (its half-diagonal is
  // 0.71 edge), the map loaded around the square as the map server would.
  std::mt19937 rng(o.seed + 11);
  std::uniform_real_distribution<double> turn(-M_PI, M_PI);
  std::vector<Pose6> priors;
  std::vector<Eigen::Vector3d> around;
  for (const BenchScan& s : scans) {
    Pose6 p = fromIsometry(s.truth);
    const double a = turn(rng);
    p.x += edge * std::cos(a);
    p.y += edge * std::sin(a);
    p.yaw = turn(rng);
    priors.push_back(p);
    around.emplace_back(p.x, p.y, 0.0);
  }
  const double radius = half * std::sqrt(2.0) + o.reg.filter.max_range_m;
  RasterStats rs;
  auto map = rasterizeAround(store, around, radius, o.raster, rs);
  if (!map.ok()) {
    std::fprintf(stderr, "global miss: %s\n", map.error().c_str());
    return rows_json;
  }
  const ScoreQuantizer q(map->options());
  out.print(
      "\n## Global search where the vehicle is not (%.0f m x %.0f m x 360 deg, centre %.0f m "
      "from it, budget %lld node scores)\n\n",
      edge, edge, edge, static_cast<long long>(budget));
  out.print(
      "| score floor [nats/pt] | scans | proved below the floor | budget stops | optimum found "
      "(best nats/pt) | search ms median / max | evaluations (median) |\n");
  out.print("|---|---|---|---|---|---|---|\n");
  // The configured floor (when it is on), then none.
  std::vector<double> floors;
  if (o.reg.global.min_score_per_point > q.floor()) {
    floors.push_back(o.reg.global.min_score_per_point);
  }
  floors.push_back(-std::numeric_limits<double>::infinity());
  for (double floor : floors) {
    GlobalSearchOptions go = o.reg.global;
    go.max_evaluations = budget;
    go.min_score_per_point = floor;
    RegistrationOptions ro = o.reg;
    ro.global = go;
    const Registration reg(ro, pool);
    const bool on = floor > q.floor();
    const std::string name = on ? "floor " + twoDecimals(floor) : "floor off";
    MissRow row;
    for (size_t i = 0; i < scans.size(); ++i) {
      MatchRequest req;
      req.prior = priors[i];
      req.half_x_m = req.half_y_m = half;
      req.half_heading_rad = M_PI;
      ScanRecord rec;
      rec.section = "global miss";
      rec.window = name;
      rec.scan = scans[i].index;
      rec.raw_points = static_cast<double>(scans[i].points.size());
      rec.offset_m = edge;
      auto prepared = reg.prepare(map.value(), scans[i].points, req);
      if (!prepared.ok()) {
        rec.failure = prepared.error();
        records->push_back(rec);
        continue;
      }
      ++row.scans;
      const double t0 = seconds();
      const GlobalSearchOutcome g = globalBranchAndBound(prepared->problem, go, pool.get());
      rec.search_ms = (seconds() - t0) * 1e3;
      row.search_ms.push_back(rec.search_ms);
      row.evaluations.push_back(static_cast<double>(g.best.stats.evaluations));
      rec.search_points = static_cast<double>(prepared->problem.scanPoints());
      if (g.below_floor) {
        ++row.below_floor;
        rec.failure = "no pose reaches the score floor";
      } else if (!g.complete) {
        ++row.budget;
        rec.failure = "global search stopped at its budget";
      } else {
        ++row.found;
        row.best_found_per_point =
            std::max(row.best_found_per_point,
                     g.best.log_likelihood / static_cast<double>(prepared->problem.scanPoints()));
        rec.failure = "an optimum in a window without the vehicle (not matched further)";
      }
      std::fprintf(stderr, "global miss %s scan %d: %s, %.0f ms, %lld evaluations\n", name.c_str(),
                   scans[i].index, rec.failure.c_str(), rec.search_ms,
                   static_cast<long long>(g.best.stats.evaluations));
      records->push_back(rec);
    }
    const std::string found = row.found > 0 ? std::to_string(row.found) + " (" +
                                                  twoDecimals(row.best_found_per_point) + ")"
                                            : "0";
    out.print("| %s | %d | %d | %d | %s | %.0f / %.0f | %.0f |\n",
              on ? twoDecimals(floor).c_str() : "off", row.scans, row.below_floor, row.budget,
              found.c_str(), median(row.search_ms), percentile(row.search_ms, 100),
              median(row.evaluations));
    JsonObject j;
    j.add("region_m", edge)
        .add("score_floor_per_point", on ? floor : std::numeric_limits<double>::quiet_NaN())
        .add("budget", static_cast<long long>(budget))
        .add("scans", row.scans)
        .add("below_floor", row.below_floor)
        .add("budget_stops", row.budget)
        .add("found", row.found)
        .add("search_ms_median", median(row.search_ms))
        .add("search_ms_max", percentile(row.search_ms, 100))
        .add("evaluations_median", median(row.evaluations));
    rows_json.push_back(j);
  }
  return rows_json;
}

}  // namespace bench
}  // namespace gmm_localization
