#pragma once
// Markdown tables and a CSV of the leave-one-out registrations (kitti_check_register.h).

#include <cstdio>
#include <string>

#include "kitti_check/kitti_check_register.h"

namespace gmm_localization {
namespace kitti_check {

/// Folds, then one table per window (per keyframe and matcher, plus all keyframes), then the
/// errors when started at the SLAM pose, then ours' discrete optimum against its refinement.
void printLooTables(const LooReport& report, std::FILE* out);

/// One row per trial: keyframe,window,matcher,offset_m,offset_deg,matched,success,error_m,
/// error_deg,error_z_m,error_long_m,error_lat_m,ms,cpu_ms,search_ms,evaluations_fraction,failure,
/// discrete_error_m,discrete_error_long_m,discrete_error_lat_m (ours' search optimum; 0 for peers).
/// False when the file cannot be written.
bool writeTrialsCsv(const LooReport& report, const std::string& path);

}  // namespace kitti_check
}  // namespace gmm_localization
