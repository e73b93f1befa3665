#pragma once
// bench_registration's command line: the options, their defaults and --help.

#include <cstdint>
#include <string>
#include <vector>

#include "bench/bench_data.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace bench {

struct BenchOptions {
  std::string map_dir;
  KittiInput scans;     ///< --scans, --poses, --kitti-calib, --point-format
  KittiInput mapping;   ///< --mapping, --mapping-poses, the same calibration and layout
  std::string out_dir;  ///< --out: per-scan CSV and the summary (markdown, JSON); empty: none
  int count = 30;
  int threads = 1;           ///< --threads: also run both windows on this many threads (1: not)
  int exhaustive_every = 3;  ///< exhaustive reference on every n-th scan of each window
  int peer_count = 20;
  PeerTargetOptions peer_target;
  uint32_t seed = 1;
  double offset_m = 10.0, offset_deg = 15.0;            ///< paper window's offsets
  double track_offset_m = 1.5, track_offset_deg = 2.5;  ///< tracking window's offsets
  double raster_radius_m = 110.0;
  bool sizes = true;
  bool global = true;
  bool memory_floor = true;  ///< --no-memory-floor: skip the memory latency and bandwidth
  int global_count = 10;
  int global_threads = 2;  ///< --global-threads: threads the global search's queues run on
  std::vector<double> global_regions_m = {25.0, 50.0, 100.0};
  /// --methods: the match methods timed side by side; height first and always (the reference
  /// of the ratios and of the other tables). Others need MAP/reflectivity and xyzi scans.
  std::vector<MatchMethod> methods = {MatchMethod::kHeight};
  RegistrationOptions reg;
  RasterOptions raster;
};

/// The --help text.
const char* benchUsage();

/// Parses argv into `o` (defaults as set by the caller). Returns false on --help or an error
/// (the message on stderr); `help` is set for --help.
bool parseBenchOptions(int argc, char** argv, BenchOptions& o, bool& help);

}  // namespace bench
}  // namespace gmm_localization
