#include "kitti_check/kitti_check_report.h"

#include <algorithm>
#include <map>
#include <set>

#include "bench/bench_data.h"
#include "evaluate/evaluate_integrity.h"

namespace gmm_localization {
namespace kitti_check {

namespace {

using bench::median;
using bench::percentile;

struct Summary {
  int runs = 0, success = 0, no_result = 0;
  std::vector<double> err_m, err_deg, err_z, ms, cpu_ms, search_ms, fraction;
};

Summary summarize(const std::vector<Trial>& trials, int keyframe, const std::string& window,
                  const std::string& matcher) {
  Summary s;
  for (const Trial& t : trials) {
    if (t.window != window || t.matcher != matcher) continue;
    if (keyframe >= 0 && t.keyframe != keyframe) continue;
    ++s.runs;
    s.success += t.success();
    s.ms.push_back(1e3 * t.seconds);
    s.cpu_ms.push_back(1e3 * t.cpu_seconds);
    if (t.matcher == "ours") {
      s.search_ms.push_back(1e3 * t.stages.search_s);
      if (t.matched) s.fraction.push_back(t.evaluations_fraction);
    }
    if (!t.matched) {
      ++s.no_result;
      continue;
    }
    s.err_m.push_back(t.error_m);
    s.err_deg.push_back(t.error_deg);
    s.err_z.push_back(t.error_z_m);
  }
  return s;
}

std::vector<std::string> ordered(const std::vector<Trial>& trials, bool window) {
  std::vector<std::string> v;
  for (const Trial& t : trials) {
    const std::string& s = window ? t.window : t.matcher;
    if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
  }
  return v;
}

void printRow(std::FILE* out, const std::string& keyframe, const std::string& matcher,
              const Summary& s) {
  char search[64] = "-";
  if (!s.search_ms.empty()) {
    std::snprintf(search, sizeof(search), "%.0f / %.2f%%", median(s.search_ms),
                  100.0 * median(s.fraction));
  }
  std::fprintf(
      out,
      "| %s | %s | %d/%d (%.0f%%) | %.3f / %.2f | %.3f / %.2f | %.3f | %.0f / %.0f | %.0f / "
      "%.0f | %s | %d |\n",
      keyframe.c_str(), matcher.c_str(), s.success, s.runs, 100.0 * s.success / std::max(1, s.runs),
      median(s.err_m), median(s.err_deg), percentile(s.err_m, 95), percentile(s.err_deg, 95),
      median(s.err_z), median(s.cpu_ms), percentile(s.cpu_ms, 99), median(s.ms),
      percentile(s.ms, 99), search, s.no_result);
}

/// Median time of each stage of our matches in window w.
void printStages(const std::vector<Trial>& trials, const std::string& w, std::FILE* out) {
  std::vector<double> f, s, h, c, o;
  for (const Trial& t : trials) {
    if (t.window != w || t.matcher != "ours") continue;
    f.push_back(1e3 * t.stages.filter_s);
    s.push_back(1e3 * t.stages.search_s);
    h.push_back(1e3 * t.stages.refine_s);
    c.push_back(1e3 * t.stages.covariance_s);
    o.push_back(1e3 * t.stages.obstacles_s);
  }
  if (f.empty()) return;
  std::fprintf(
      out,
      "\nours, median wall ms per stage: filter, levelling, height pre-alignment and rotations "
      "%.1f; search %.1f; hill climb %.1f; covariance %.1f; obstacle labels %.1f\n",
      median(f), median(s), median(h), median(c), median(o));
}

/// Ours' certificates in window w, as `evaluate` summarizes a drive's: availability, certified
/// matches wrong beyond their protection level or the alert limit (hazardously misleading), the
/// SLAM pose's score deficit. Matches without a result are not registrations.
void printIntegrity(const std::vector<Trial>& trials, const std::string& w, std::FILE* out) {
  eval::IntegritySummary s;
  for (const Trial& t : trials) {
    if (t.window == w && t.matcher == "ours" && t.matched) {
      eval::addToIntegrity(t.integrity, t.error_m, s);
    }
  }
  eval::finishIntegrity(s);
  std::fprintf(out, "\n%s", eval::integrityMarkdown(s, "ours, " + w).c_str());
}

/// Ours' discrete optimum against its refined pose and against GICP from the same starts, per
/// keyframe and window ("SLAM pose" included): median horizontal errors and how often the
/// refinement ends at least as close to the SLAM pose as the discrete optimum (1 mm slack).
void printRefinement(const LooReport& r, std::FILE* out) {
  const std::vector<std::string> windows = ordered(r.trials, true);
  std::fprintf(out,
               "\n## The refinement against the discrete optimum\n\nHorizontal error against "
               "the SLAM pose [m], medians over the starts; GICP from the same starts.\n\n| "
               "window | keyframe | starts | ours discrete optimum | ours refined | refined <= "
               "discrete + 1 mm | PCL GICP |\n|---|---|---|---|---|---|---|\n");
  for (const std::string& w : windows) {
    std::vector<int> keys;
    for (const Fold& f : r.folds) keys.push_back(f.keyframe);
    keys.push_back(-1);
    for (int k : keys) {
      std::vector<double> disc, ref, gicp;
      int not_worse = 0;
      for (const Trial& t : r.trials) {
        if (t.window != w || (k >= 0 && t.keyframe != k) || !t.matched) continue;
        if (t.matcher == "ours") {
          disc.push_back(t.discrete_error_m);
          ref.push_back(t.error_m);
          not_worse += t.error_m <= t.discrete_error_m + 1e-3;
        } else if (t.matcher == "PCL GICP") {
          gicp.push_back(t.error_m);
        }
      }
      if (disc.empty()) continue;
      char g[32] = "-";
      if (!gicp.empty()) std::snprintf(g, sizeof(g), "%.3f", median(gicp));
      const std::string key = k >= 0 ? std::to_string(k) : "**all**";
      std::fprintf(out, "| %s | %s | %zu | %.3f | %.3f | %d/%zu | %s |\n", w.c_str(), key.c_str(),
                   disc.size(), median(disc), median(ref), not_worse, disc.size(), g);
    }
  }
}

}  // namespace

void printLooTables(const LooReport& r, std::FILE* out) {
  std::fprintf(out, "## Leave-one-out folds\n\n");
  std::fprintf(
      out,
      "| held-out keyframe | map keyframes | nearest mapped keyframe | map cells with data "
      "| scan voxels over mapped cells (at the SLAM pose) |\n|---|---|---|---|---|\n");
  for (const Fold& f : r.folds) {
    std::string keys;
    for (int i : f.map_keyframes) keys += (keys.empty() ? "" : ",") + std::to_string(i);
    std::fprintf(out, "| %d | %s | %.1f m | %llu | %.0f%% |\n", f.keyframe, keys.c_str(),
                 f.nearest_map_keyframe_m, static_cast<unsigned long long>(f.map_cells),
                 100.0 * f.overlap);
  }
  const std::vector<std::string> matchers = ordered(r.trials, false);
  for (const std::string& w : ordered(r.trials, true)) {
    if (w == "SLAM pose") continue;
    std::fprintf(out, "\n## %s\n\n", w.c_str());
    std::fprintf(
        out,
        "| keyframe | matcher | success <0.5 m, <1 deg | error median m / deg | error p95 "
        "m / deg | median abs z error m | CPU ms per match median / p99 | wall ms per match "
        "median / p99 | ours: search wall ms median / evaluations %% of exhaustive | no result "
        "|\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Fold& f : r.folds) {
      for (const std::string& m : matchers) {
        printRow(out, std::to_string(f.keyframe), m, summarize(r.trials, f.keyframe, w, m));
      }
    }
    for (const std::string& m : matchers) {
      printRow(out, "**all**", "**" + m + "**", summarize(r.trials, -1, w, m));
    }
    printStages(r.trials, w, out);
    printIntegrity(r.trials, w, out);
  }
  std::fprintf(out, "\n## Started at the SLAM pose (paper window for ours)\n\n");
  std::fprintf(out,
               "Signed errors along / across the heading (x forward, y left) [m], heading error "
               "[deg], |z error| [m].\n\n| keyframe |");
  for (const std::string& m : matchers) {
    std::fprintf(out, " %s along / across / deg / z |", m.c_str());
  }
  std::fprintf(out, "\n|---|");
  for (size_t i = 0; i < matchers.size(); ++i) std::fprintf(out, "---|");
  std::fprintf(out, "\n");
  for (const Fold& f : r.folds) {
    std::fprintf(out, "| %d |", f.keyframe);
    for (const std::string& m : matchers) {
      const Trial* t = nullptr;
      for (const Trial& c : r.trials) {
        if (c.keyframe == f.keyframe && c.window == "SLAM pose" && c.matcher == m) t = &c;
      }
      if (t == nullptr || !t->matched) {
        std::fprintf(out, " no result |");
      } else {
        std::fprintf(out, " %+.3f / %+.3f / %.2f / %.3f |", t->error_long_m, t->error_lat_m,
                     t->error_deg, t->error_z_m);
      }
    }
    std::fprintf(out, "\n");
  }
  printRefinement(r, out);
  // Failure reasons of ours, counted.
  std::map<std::string, int> reasons;
  for (const Trial& t : r.trials) {
    if (t.matcher == "ours" && !t.matched) ++reasons[t.failure];
  }
  if (!reasons.empty()) {
    std::fprintf(out, "\nours, no result:\n");
    for (const auto& [why, n] : reasons) std::fprintf(out, "- %d x %s\n", n, why.c_str());
  }
}

bool writeTrialsCsv(const LooReport& r, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  std::fprintf(
      f,
      "keyframe,window,matcher,offset_m,offset_deg,matched,success,error_m,error_deg,"
      "error_z_m,error_long_m,error_lat_m,ms,cpu_ms,search_ms,evaluations_fraction,failure,"
      "discrete_error_m,discrete_error_long_m,discrete_error_lat_m,certified,"
      "certificate_failure,protection_xy_m,truth_deficit_per_point\n");
  for (const Trial& t : r.trials) {
    std::string why = t.failure, window = t.window;
    std::replace(why.begin(), why.end(), ',', ';');
    std::replace(window.begin(), window.end(), ',', ';');
    std::fprintf(
        f,
        "%d,%s,%s,%.4f,%.4f,%d,%d,%.5f,%.5f,%.5f,%.5f,%.5f,%.3f,%.3f,%.3f,%.6f,%s,%.5f,%.5f,%.5f,"
        "%d,%s,%.4f,%.6f\n",
        t.keyframe, window.c_str(), t.matcher.c_str(), t.offset_m, t.offset_deg, t.matched ? 1 : 0,
        t.success() ? 1 : 0, t.error_m, t.error_deg, t.error_z_m, t.error_long_m, t.error_lat_m,
        1e3 * t.seconds, 1e3 * t.cpu_seconds, 1e3 * t.stages.search_s, t.evaluations_fraction,
        why.c_str(), t.discrete_error_m, t.discrete_error_long_m, t.discrete_error_lat_m,
        t.integrity.certified ? 1 : 0, t.integrity.failure.c_str(), t.integrity.protection_xy_m,
        t.integrity.truth_deficit_per_point);
  }
  return std::fclose(f) == 0;
}

}  // namespace kitti_check
}  // namespace gmm_localization
