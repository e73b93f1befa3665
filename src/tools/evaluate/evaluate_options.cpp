#include "evaluate/evaluate_options.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace gmm_localization {
namespace eval {
namespace {

double toDouble(const std::string& key, const std::string& v) {
  try {
    size_t used = 0;
    const double d = std::stod(v, &used);
    if (used == v.size() && std::isfinite(d)) return d;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(key + ": '" + v + "' is not a number");
}

std::vector<double> toDoubles(const std::string& key, const std::string& v, size_t n) {
  std::vector<double> out;
  std::stringstream s(v);
  std::string part;
  while (std::getline(s, part, ',')) out.push_back(toDouble(key, part));
  if (out.size() != n) {
    throw std::invalid_argument(key + ": expected " + std::to_string(n) +
                                " comma-separated numbers, got '" + v + "'");
  }
  return out;
}

}  // namespace

const char* evaluateUsage() {
  return R"(evaluate: score localization against ground truth (paper section V: Table I, Fig. 8-10).

Mode A, read a localization bag directly (deterministic, faster than real time):
  evaluate bag --bag drive.bag --map MAP_DIR --out DIR [options]
    --dataset NAME          downtown | snowy | any label (picks the paper's row) [downtown]
    --config-dir DIR        matcher.yaml, ekf.yaml, map_server.yaml [the package's config/]
    --matcher-param K=V     override a matcher.yaml key (YAML value), repeatable
    --ekf-param K=V         override an ekf.yaml key, repeatable
    --latency S             virtual match processing time [s], or 'measured' [0.1]
    --arrival-delay S       scan arrival after its stamp [s], or 'auto' (bag record delay) [auto]
    --global-latency S      a global search's virtual time [s], or 'measured' (its wall time,
                            as in the matcher's global worker) [measured]
    --initial-offset DX,DY,DYAW_DEG   initial pose = truth at the first scan + this [2,-1.5,2]
    --ekf-rate HZ           EKF error sampling rate [20]
    --raster-radius M       map chunks within this of the route [100]
    --threads N             map rasterization threads [2]
    --duration S            evaluate only the first S seconds of the bag [all]
    --offset-scans N        scans used for the random-offset experiment (Fig. 8), 0: none [100]
    --offset-trials K       random offsets per scan [1]
    --offset-radius M       offsets uniform within this radius [10]
    --offset-heading DEG    and within +-this heading [15]
    --seed N                offset generator seed [1]
    --quiet                 no progress bar on stderr
    --cloud-topic T --odom-topic T --imu-topic T --gt-topic T   [/velodyne_points /ins/odom
                            /imu/data /ground_truth/odom]

Mode B, score a recording of a real replay (roslaunch gmm_localization replay.launch record:=R):
  evaluate recorded --bag R --out DIR [--source-bag PLAYED.bag] [--dataset NAME]
    [--gt-topic /ground_truth/odom] [--ekf-topic /localization/odometry]
    [--status-topic /localization/status] [--ekf-rate HZ (0: all)]

Both modes:
    --method M              height (the paper's) | reflectivity (the Levinson baseline: mode A
                            matches against MAP_DIR/reflectivity, built by build_map --layer
                            reflectivity, with the matcher's method: reflectivity) | fused
                            (both likelihoods summed: mode A matches against MAP_DIR and
                            MAP_DIR/reflectivity); mode B: the label of the replay's method
                            [height]
    --world LABEL           a label of the simulated world (e.g. perfect, imperfect), kept in
                            summary.json and used by plot_evaluation.py to group Table I
    --gps                   with GPS (the paper's Table I asterisk): mode A fuses the bag's
                            GNSS fixes (simulate --gnss realistic) in the EKF (ekf.yaml
                            gnss/enabled true; the map needs a georeference); mode B: the
                            replay ran with gnss:=true. Recorded as "gps" in summary.json
    --map-poses DIR         a map built from inexact poses: DIR holds the poses it was built
                            from (poses.txt) and their truth (poses_truth.txt, written by
                            simulate --map-pose-error); the errors are also reported against
                            the truth moved into the map's frame, and the map's own error

Output: ekf.csv, matches.csv, offsets.csv, traversal.ppm (+ .json), summary.json, summary.md;
scripts/plot_evaluation.py draws the figures and Table I from one or more output directories.
Exit status: 0 scored; 1 failed (the reason on stderr); 2 bad arguments; 3 no data (neither an
EKF estimate nor an accepted match met a ground-truth pose: the summary says so, no RMS).
)";
}

EvaluateCommand parseEvaluateCommand(int argc, char** argv, const std::string& default_config_dir) {
  EvaluateCommand c;
  if (argc < 2) return c;
  const std::string mode = argv[1];
  if (mode == "bag") {
    c.mode = EvaluateCommand::Mode::kBag;
  } else if (mode == "recorded") {
    c.mode = EvaluateCommand::Mode::kRecorded;
  } else if (mode == "-h" || mode == "--help" || mode == "help") {
    return c;
  } else {
    throw std::invalid_argument("unknown mode '" + mode + "' (bag or recorded)");
  }
  std::string config_dir = default_config_dir;
  BagEvaluationConfig& b = c.bag;
  RecordedEvaluationConfig& r = c.recorded;
  for (int i = 2; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "-h" || key == "--help") {
      c.mode = EvaluateCommand::Mode::kHelp;
      return c;
    }
    if (key == "--quiet") {
      b.progress = false;
      continue;
    }
    if (key == "--gps") {
      c.gps = true;
      if (c.mode == EvaluateCommand::Mode::kBag) b.ekf_overrides.push_back("gnss/enabled=true");
      continue;
    }
    if (i + 1 >= argc) throw std::invalid_argument(key + " needs a value");
    const std::string v = argv[++i];
    const bool bag = c.mode == EvaluateCommand::Mode::kBag;
    if (key == "--bag") {
      b.bag = r.bag = v;
    } else if (key == "--out") {
      c.out = v;
    } else if (key == "--method") {
      if (v != "height" && v != "reflectivity" && v != "fused") {
        throw std::invalid_argument("--method: '" + v + "' is not height, reflectivity or fused");
      }
      c.method = v;
    } else if (key == "--world") {
      c.world = v;
    } else if (key == "--map-poses") {
      c.map_poses = v;
    } else if (key == "--dataset") {
      b.dataset = r.dataset = v;
    } else if (key == "--gt-topic") {
      b.topics.ground_truth = r.topics.ground_truth = v;
    } else if (key == "--ekf-rate") {
      b.ekf_rate_hz = r.ekf_rate_hz = toDouble(key, v);
      if (bag && !(b.ekf_rate_hz > 0.0)) throw std::invalid_argument("--ekf-rate must be > 0");
    } else if (key == "--cloud-topic") {
      b.topics.cloud = r.cloud_topic = v;
    } else if (bag && key == "--map") {
      b.map = v;
    } else if (bag && key == "--config-dir") {
      config_dir = v;
    } else if (bag && key == "--matcher-param") {
      b.matcher_overrides.push_back(v);
    } else if (bag && key == "--ekf-param") {
      b.ekf_overrides.push_back(v);
    } else if (bag && key == "--latency") {
      b.latency_s = v == "measured" ? -1.0 : toDouble(key, v);
    } else if (bag && key == "--global-latency") {
      b.global_latency_s = v == "measured" ? -1.0 : toDouble(key, v);
    } else if (bag && key == "--arrival-delay") {
      b.arrival_delay_s = v == "auto" ? -1.0 : toDouble(key, v);
    } else if (bag && key == "--initial-offset") {
      const auto d = toDoubles(key, v, 3);
      b.initial_dx_m = d[0];
      b.initial_dy_m = d[1];
      b.initial_dyaw_rad = d[2] * M_PI / 180.0;
    } else if (bag && key == "--raster-radius") {
      b.raster_radius_m = toDouble(key, v);
    } else if (bag && key == "--threads") {
      b.threads = static_cast<int>(toDouble(key, v));
    } else if (bag && key == "--duration") {
      b.max_duration_s = toDouble(key, v);
    } else if (bag && key == "--offset-scans") {
      b.offset_scans = static_cast<int>(toDouble(key, v));
    } else if (bag && key == "--offset-trials") {
      b.offsets.trials_per_scan = std::max(1, static_cast<int>(toDouble(key, v)));
    } else if (bag && key == "--offset-radius") {
      b.offsets.radius_m = toDouble(key, v);
    } else if (bag && key == "--offset-heading") {
      b.offsets.max_heading_rad = toDouble(key, v) * M_PI / 180.0;
    } else if (bag && key == "--seed") {
      b.offsets.seed = static_cast<uint64_t>(toDouble(key, v));
    } else if (bag && key == "--odom-topic") {
      b.topics.odom = v;
    } else if (bag && key == "--imu-topic") {
      b.topics.imu = v;
    } else if (!bag && key == "--source-bag") {
      r.source_bag = v;
    } else if (!bag && key == "--ekf-topic") {
      r.topics.ekf = v;
    } else if (!bag && key == "--status-topic") {
      r.topics.status = v;
    } else {
      throw std::invalid_argument("unknown option " + key + " for mode " + mode);
    }
  }
  if (b.bag.empty()) throw std::invalid_argument("--bag is required");
  if (c.out.empty()) throw std::invalid_argument("--out is required");
  if (c.mode == EvaluateCommand::Mode::kBag && b.map.empty()) {
    throw std::invalid_argument("--map is required in mode bag");
  }
  if (c.mode == EvaluateCommand::Mode::kBag && c.method == "reflectivity") {
    b.map += "/reflectivity";
    b.matcher_overrides.insert(b.matcher_overrides.begin(), "method=reflectivity");
  }
  if (c.mode == EvaluateCommand::Mode::kBag && c.method == "fused") {
    b.reflectivity_map = b.map + "/reflectivity";
    b.matcher_overrides.insert(b.matcher_overrides.begin(), "method=fused");
  }
  b.matcher_yaml = config_dir + "/matcher.yaml";
  b.ekf_yaml = config_dir + "/ekf.yaml";
  b.map_server_yaml = config_dir + "/map_server.yaml";
  return c;
}

}  // namespace eval
}  // namespace gmm_localization
