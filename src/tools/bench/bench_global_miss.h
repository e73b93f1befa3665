#pragma once
// bench_registration's section on global searches in windows that do not hold the vehicle (a
// start sweep's other windows, a kidnap's stale prior): how they end, with the score floor
// (GlobalSearchOptions::min_score_per_point) and without it.

#include <memory>
#include <vector>

#include "bench/bench_data.h"
#include "bench/bench_options.h"
#include "bench/bench_output.h"
#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/map/map_store.h"

namespace gmm_localization {
namespace bench {

/// For the largest of o.global_regions_m: each scan's window centred `edge` metres from its
/// truth in a seeded random direction (so the vehicle is outside the square), any heading;
/// searched with the configured floor (when it is on) and without one, at the node budget (or
/// the matcher's default when the benchmark's is unlimited). Prints the table, appends one
/// record per search and returns the rows as JSON.
std::vector<JsonObject> benchGlobalMiss(Report& out, const MapStore& store,
                                        const std::vector<BenchScan>& scans, const BenchOptions& o,
                                        const std::shared_ptr<TaskPool>& pool,
                                        std::vector<ScanRecord>* records);

}  // namespace bench
}  // namespace gmm_localization
