#pragma once
// Command line of `evaluate` (evaluate --help prints the usage below).

#include <string>

#include "evaluate/evaluate_localize.h"
#include "evaluate/evaluate_recorded.h"

namespace gmm_localization {
namespace eval {

struct EvaluateCommand {
  enum class Mode { kHelp, kBag, kRecorded } mode = Mode::kHelp;
  std::string out;                ///< output directory
  std::string world;              ///< --world: a label of the simulated world, kept in the summary
  std::string method = "height";  ///< --method: height, reflectivity or fused
  std::string map_poses;  ///< --map-poses: mapping poses + their truth (evaluate_map_frame.h)
  bool gps = false;       ///< --gps: the EKF fuses the bag's GNSS fixes (mode B: a label)
  BagEvaluationConfig bag;
  RecordedEvaluationConfig recorded;
};

/// Parses argv; throws std::invalid_argument with a message naming the bad option.
EvaluateCommand parseEvaluateCommand(int argc, char** argv, const std::string& default_config_dir);

const char* evaluateUsage();

}  // namespace eval
}  // namespace gmm_localization
