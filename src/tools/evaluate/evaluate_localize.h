#pragma once
// Mode A of `evaluate`: reads a localization bag directly and runs it through LocalizerPipeline
// (the matcher and ekf nodelets' logic on a virtual clock, core/localization/localizer_pipeline.h)
// with the nodelets' options loaded from the same YAML files, then scores the EKF output, the
// raw matches, the obstacle labels and (optionally) registrations from random offsets against
// the bag's ground truth. Deterministic when the match latency is fixed (the default).

#include <cstdint>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include "evaluate/evaluate_bag.h"
#include "evaluate/evaluate_offsets.h"
#include "evaluate/evaluate_results.h"

namespace gmm_localization {
namespace eval {

struct BagEvaluationConfig {
  std::string bag;
  std::string map;  ///< the layer matched (MAP, or MAP/reflectivity for --method reflectivity)
  /// --method fused: the second map, MAP/reflectivity (empty otherwise).
  std::string reflectivity_map;
  std::string matcher_yaml, ekf_yaml, map_server_yaml;
  std::vector<std::string> matcher_overrides, ekf_overrides;  ///< "key=value" (YAML value)
  BagTopics topics;
  std::string dataset = "downtown";
  /// Match processing time on the virtual clock [s]; < 0: the measured time (not deterministic).
  double latency_s = 0.1;
  /// A global search's time on the virtual clock [s]; < 0: its measured wall time, as on the
  /// vehicle (the global worker; the scans meanwhile are skipped or searched in the interim
  /// window). A fixed short time would start a global search at nearly every scan while lost.
  double global_latency_s = -1.0;
  /// Scan arrival after its stamp [s]; < 0: the bag's median record delay.
  double arrival_delay_s = -1.0;
  double ekf_rate_hz = 20.0;  ///< EKF output sampling rate for the error series [Hz]
  /// Initial pose (unless matcher.yaml enables its own): the truth at the first scan moved by
  /// these (map frame [m], [m], [rad]), as a GPS fix would be.
  double initial_dx_m = 2.0, initial_dy_m = -1.5, initial_dyaw_rad = 2.0 * M_PI / 180.0;
  double raster_radius_m = 100.0;  ///< map chunks within this of the route [m]
  int threads = 2;                 ///< map rasterization threads
  double max_duration_s = std::numeric_limits<double>::infinity();  ///< of the bag [s]
  int offset_scans = 100;  ///< scans used for Fig. 8 (evenly spread; 0: none)
  OffsetOptions offsets;
  bool progress = true;  ///< a progress bar on stderr (evaluate --quiet: none)
};

/// Runs mode A; progress lines go to `log`. Fails with the reason (options, bag, map).
Result<EvaluationResults> runBagEvaluation(const BagEvaluationConfig& config, std::ostream& log,
                                           TraversalFigure* traversal);

}  // namespace eval
}  // namespace gmm_localization
