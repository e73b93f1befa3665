#pragma once
// evaluate --gps (mode A): the bag's GNSS fixes into the pipeline's EKF, as the ekf nodelet with
// gnss/enabled fuses them (the paper's reflectivity baseline in snow ran "with GPS"). The fixes
// are placed in the map frame with the map's georeference (its manifest; for a layer directory
// such as MAP/reflectivity without one, the height map's beside it), and counted in the run's
// summary. While the EKF is not running (no match started it) the fixes also give it and the
// matcher an initial pose, as the vehicle's GNSS initializer does (gnss_initializer:=true: course
// over ground, core/localization/gnss_initial_pose.h).

#include <iosfwd>
#include <string>

#include "evaluate/evaluate_bag.h"
#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/localization/localizer_pipeline.h"
#include "gmm_localization/ros/ekf_node_options.h"

namespace gmm_localization {
namespace eval {

/// The georeference of a map directory (or of its parent, for a layer directory without one).
/// Fails, naming the build_map options that give one, when neither has a UTM grid.
Result<Georeference> mapGeoreference(const std::string& map_directory);

/// With ekf.filter.gnss_enabled: sets the pipeline's georeference and visitor->gnss (feeding
/// `pipeline`, counting into out->info), and marks the run as "with GPS". Without: nothing.
/// `pipeline` and `out` must outlive the visit.
Status attachGnss(const node::EkfNodeOptions& ekf, const std::string& map_directory,
                  LocalizerPipeline* pipeline, BagVisitor* visitor, EvaluationResults* out,
                  std::ostream& log);

}  // namespace eval
}  // namespace gmm_localization
