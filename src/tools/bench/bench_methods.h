#pragma once
// bench_registration's match methods (--methods): the height matcher (the paper's, always run:
// the reference of the ratios and of every other table), the reflectivity matcher (the
// scan's ground returns, intensity as the value, against MAP/reflectivity over x, y and
// heading) and the fused one (both likelihoods summed in one search), each set up as
// MatchProcessor sets it up (core/localization/match_processor.cpp) and timed on the same scans
// and priors as the height matcher, scan by scan; and the methods table with the ratios to
// height of the same run.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/bench_data.h"
#include "bench/bench_output.h"
#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {
namespace bench {

/// What one match returned, compared bit for bit between runs on different thread counts.
struct MatchKey {
  std::string failure;  ///< empty when a pose came out
  int heading_index = 0, tx = 0, ty = 0;
  int64_t score = 0;
  double pose[6] = {0, 0, 0, 0, 0, 0};
  double refined_score = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  bool certified = false;
  size_t obstacles = 0;
  bool operator==(const MatchKey& o) const;
};

/// One row of a window table: every registration of one matcher in one window.
struct WindowRow {
  std::string name;
  std::string matcher = "gmm_localization";  ///< the CSV's matcher column
  MatchMethod method = MatchMethod::kHeight;
  std::vector<double> filter_ms, search_ms, filter_search_ms, total_ms, fraction, error_m,
      error_deg;
  std::vector<double> refine_ms, covariance_ms, obstacles_ms, certificate_ms;
  /// The refinement's trials per match, and those of them passed over as repeats (unscored).
  std::vector<double> refine_trials, refine_repeated;
  std::vector<double> points, lookups;     ///< search points per heading; evaluations x points
  int certified = 0, certified_wrong = 0;  ///< certified matches; of them outside success
  int success = 0, runs = 0, equal = 0, compared = 0, failures = 0;
  std::vector<double> exhaustive_ms;
  std::vector<ScanRecord> records;  ///< one per registration, for --out
  std::vector<MatchKey> results;    ///< one per registration, to compare thread counts
  int threads = 1;
};

/// "height,reflectivity,fused" (any subset, any order; "all": the three) into `out`, height
/// first and always (the reference); false for an unknown name or an empty list.
bool parseMethodList(const std::string& text, std::vector<MatchMethod>* out);

/// True when a method other than height is listed (the reflectivity layer is needed).
bool needsReflectivityLayer(const std::vector<MatchMethod>& methods);

/// The reflectivity layer beside the height map, MAP_DIR/reflectivity, opened and checked to
/// hold that layer. The failure names the directory, why, and the build_map command.
Result<MapStore> openReflectivityLayer(const std::string& map_dir);

/// A method's matcher: the registration and the maps it searches, and how it turns a scan and
/// a height request into its own (as MatchProcessor::process does).
struct MethodMatcher {
  MethodMatcher(MatchMethod method, const RegistrationOptions& height_options,
                const ChunkMap& height_map, const ChunkMap* reflectivity_map,
                const ReflectivityLayerOptions& layer);
  MatchMethod method;
  Registration registration;  ///< the height options, or reflectivityRegistrationOptions
  const ChunkMap* map;        ///< the map searched: the height map, or the reflectivity layer
  const ChunkMap* reflectivity_map;  ///< the fused method's second channel
  ReflectivityLayerOptions layer;    ///< the layer's definition (from its manifest)

  /// The points to register and the request: the scan itself (height); its ground returns,
  /// levelled by the prior's roll and pitch, intensity as value, prior z, roll and pitch 0
  /// (reflectivity); the scan with its ground returns as `channel` (fused). `own` and
  /// `channel` hold what the returned points and `req` refer to.
  const PointList& input(const BenchScan& scan, MatchRequest& req, PointList& own,
                         FusedChannel& channel) const;
};

/// The methods table: for each window, a row per method, with the stages' median times, the
/// success and the errors against the truth, and the ratios to the height row of that window
/// (`windows[w][0]`, same scans and priors). Returns the rows as JSON.
std::vector<JsonObject> printMethods(Report& out,
                                     const std::vector<std::vector<WindowRow>>& windows);

}  // namespace bench
}  // namespace gmm_localization
