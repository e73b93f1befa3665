#pragma once
// Command-line options of `simulate` (parsing and --help text).

#include <string>

#include "gmm_localization/sim/map_pose_error.h"
#include "gmm_localization/sim/simulation.h"
#include "simulate/simulate_bag_writer.h"
#include "simulate/simulate_gnss.h"
#include "simulate/simulate_imperfection_options.h"

namespace gmm_localization {
namespace tools {

struct SimulateOptions {
  sim::SimulationConfig config;
  BagOptions bag;         // bag.path empty = no bag
  std::string kitti_dir;  // empty = no KITTI output
  int kitti_every = 1;
  bool kitti_labels = false;
  sim::MapPoseErrorConfig map_pose_error;  // error of the poses written to poses.txt
  SimulateGnssOptions gnss;                // --gnss: fixes on /gnss/fix (bag only)
  bool quiet = false;
  bool dry_run = false;
  bool help = false;
};

/// Parses argv; the failure names the option and the problem.
Result<SimulateOptions> parseSimulateOptions(int argc, char** argv);
const char* simulateHelp();

}  // namespace tools
}  // namespace gmm_localization
