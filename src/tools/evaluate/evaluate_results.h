#pragma once
// What `evaluate` measures, as rows (one CSV each) plus the run's context, and the summary
// (Table I, Fig. 8 success rate, match rate and latency, obstacle precision / recall) written
// as summary.json and summary.md (evaluate_report.cpp). Both modes fill the same structures.

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "evaluate/evaluate_metrics.h"

namespace gmm_localization {
namespace eval {

/// With `evaluate --map-poses` (evaluate_map_frame.h): the map's own error where the vehicle
/// is (the truth in the map's frame against the truth) and the estimate against the truth in
/// the map's frame (the localization's own error). Both valid only when `valid`.
struct MapFrameErrors {
  bool valid = false;
  VehicleFrameError map;
  VehicleFrameError in_map;
};

/// The EKF output at one time against the ground truth (Fig. 10).
struct EkfRow {
  double t = 0.0;
  PoseStamped2 estimate, truth;
  VehicleFrameError error;
  double sigma_x_m = 0.0, sigma_y_m = 0.0, sigma_yaw_rad = 0.0;
  MapFrameErrors map_frame;
  /// The EKF's INS twist scale s (twist = (1 + s) v); NaN when unknown (a recording).
  double twist_scale = std::numeric_limits<double>::quiet_NaN();
  /// The EKF's GNSS receiver bias estimate, map frame [m] (NaN in mode B).
  double gnss_bias_x_m = std::numeric_limits<double>::quiet_NaN();
  double gnss_bias_y_m = std::numeric_limits<double>::quiet_NaN();
};

/// A registration's certificate and the truth's score deficit (docs/integrity.md).
struct IntegrityFields {
  bool valid = false;  ///< a registration result exists
  bool certified = false;
  std::string failure;  ///< "" when certified
  double protection_xy_m = 0.0, protection_heading_rad = 0.0;
  double separation_per_point = 0.0;
  double truth_deficit_per_point = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no truth
  double certificate_ms = 0.0;
};

/// One scan through the matcher.
struct MatchRow {
  double stamp_s = 0.0;
  std::string outcome;  ///< accepted | rejected | skipped
  std::string reason;
  std::string prior_source;
  bool wide = false;
  double window_half_x_m = 0.0, window_half_heading_rad = 0.0;
  uint64_t input_points = 0, search_points = 0;
  uint64_t evaluations = 0;
  double search_fraction = 0.0;
  double log_likelihood_per_point = 0.0, map_coverage = 0.0;
  double filter_ms = 0.0, search_ms = 0.0, refine_ms = 0.0, total_ms = 0.0;  ///< measured
  double latency_s = 0.0;  ///< result available - scan stamp [s]
  uint32_t dropped_before = 0;
  std::string fuse;       ///< the EKF's verdict on an accepted match ("" when not offered)
  bool has_pose = false;  ///< a registration result with ground truth at the stamp
  PoseStamped2 pose, truth;
  VehicleFrameError error;
  MapFrameErrors map_frame;
  Confusion obstacles;  ///< this scan's classification (labelled clouds only)
  IntegrityFields integrity;
};

/// One registration from a random offset (Fig. 8).
struct OffsetRow {
  double stamp_s = 0.0;
  PlanarOffset offset;
  bool has_result = false, accepted = false;
  std::string reason;
  double error_m = 0.0, error_yaw_rad = 0.0;  ///< result - truth (planar distance, heading)
  uint64_t evaluations = 0;
  double search_fraction = 0.0, search_ms = 0.0, total_ms = 0.0;
  IntegrityFields integrity;
};

/// Obstacle classification against the simulator's labels (obstacle = label != 0).
struct ObstacleStats {
  Confusion all;
  /// Horizontal range bins from base_link: [0, 20), [20, 40), [40, 60), [60, inf) m.
  std::array<Confusion, 4> by_range;
  /// Recall per true label: 1 (dynamic or changed), 2 (snow).
  std::array<uint64_t, 3> positives_by_label{}, detected_by_label{};
  uint64_t scans = 0;

  /// Share of the points of true label `label` (1 or 2) labelled obstacle; NaN without any.
  double labelRecall(int label) const {
    return positives_by_label[label] ? static_cast<double>(detected_by_label[label]) /
                                           static_cast<double>(positives_by_label[label])
                                     : std::numeric_limits<double>::quiet_NaN();
  }
};

/// The run's context for the summary.
struct RunInfo {
  std::string mode;     ///< "bag" (mode A) or "recorded" (mode B)
  std::string dataset;  ///< downtown | snowy | any label (chooses the paper's row)
  std::string world;    ///< a label of the simulated world (e.g. perfect, imperfect); may be empty
  std::string method = "height";  ///< what was matched (height, reflectivity, fused)
  std::string map_poses;  ///< --map-poses directory (empty: errors against the exact truth only)
  std::string bag;
  std::string map;
  double duration_s = 0.0;          ///< bag time span evaluated [s]
  double wall_s = 0.0;              ///< evaluation wall time (excluding the map) [s]
  double map_wall_s = 0.0;          ///< map rasterization wall time [s]
  double virtual_latency_s = -1.0;  ///< fixed match latency used (mode A; < 0: measured)
  double scan_arrival_delay_s = 0.0;
  uint64_t scans_in_bag = 0;
  uint64_t dropped_scans = 0;
  uint64_t ekf_inactive_samples = 0;  ///< sample times at which the filter was not running
  std::string traversal_image;        ///< file name, empty when none
  /// evaluate --gps: the bag's GNSS fixes were fused by the EKF ("with GPS" in Table I), and
  /// what became of them.
  bool gps = false;
  uint64_t gnss_fixes = 0, gnss_fused = 0, gnss_gated = 0, gnss_refused = 0;
  uint64_t gnss_filter_not_running = 0;
  std::vector<std::string> notes;
};

struct EvaluationResults {
  RunInfo info;
  std::vector<EkfRow> ekf;
  std::vector<MatchRow> matches;
  std::vector<OffsetRow> offsets;
  ObstacleStats obstacles;
  bool has_obstacles = false;
};

/// Writes ekf.csv, matches.csv, offsets.csv (when any), summary.json and summary.md into
/// `directory` (created). Returns the summary markdown (also printed by the tool), or throws
/// std::runtime_error naming a file that cannot be written.
std::string writeResults(const EvaluationResults& results, const std::string& directory);

/// The paper's Table I row of the proposed method for a dataset label: {longitudinal, lateral}
/// RMS [m]; {0, 0} when unknown.
std::array<double, 2> paperRms(const std::string& dataset);

}  // namespace eval
}  // namespace gmm_localization
