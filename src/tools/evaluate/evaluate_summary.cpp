#include "evaluate/evaluate_summary.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "evaluate/evaluate_format.h"

namespace gmm_localization {
namespace eval {
namespace {

constexpr double kSuccessM = 0.5;  // Fig. 8: "within 0.5 m of the ground truth"

/// The accuracy targets {longitudinal, lateral} RMS [m] for a dataset; {0, 0} when none.
std::array<double, 2> targetRms(const std::string& dataset) {
  if (dataset == "downtown") return {0.075, 0.05};
  if (dataset == "snowy") return {0.09, 0.06};
  return {0.0, 0.0};
}

std::string jsonString(const std::string& v) {
  std::string out = "\"";
  for (char c : v) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string cm(double m) {
  if (!std::isfinite(m)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << m * 100.0 << " cm";
  return s.str();
}

std::string pct(double share) {
  if (!std::isfinite(share)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << share * 100.0 << "%";
  return s.str();
}

std::string errorJson(const ErrorSummary& e) {
  std::ostringstream s;
  s << "{\"count\": " << e.count << ", \"rms_longitudinal_m\": " << num(e.rms_longitudinal_m)
    << ", \"rms_lateral_m\": " << num(e.rms_lateral_m)
    << ", \"rms_yaw_rad\": " << num(e.rms_yaw_rad)
    << ", \"mean_abs_longitudinal_m\": " << num(e.mean_abs_longitudinal_m)
    << ", \"mean_abs_lateral_m\": " << num(e.mean_abs_lateral_m)
    << ", \"p95_planar_m\": " << num(e.p95_planar_m)
    << ", \"max_planar_m\": " << num(e.max_planar_m) << "}";
  return s.str();
}

std::string quantilesJson(const Quantiles& q) {
  std::ostringstream s;
  s << "{\"count\": " << q.count << ", \"p50\": " << num(q.p50) << ", \"p95\": " << num(q.p95)
    << ", \"max\": " << num(q.max) << ", \"mean\": " << num(q.mean) << "}";
  return s.str();
}

std::string confusionJson(const Confusion& c) {
  std::ostringstream s;
  s << "{\"tp\": " << c.tp << ", \"fp\": " << c.fp << ", \"fn\": " << c.fn << ", \"tn\": " << c.tn
    << ", \"precision\": " << num(c.precision()) << ", \"recall\": " << num(c.recall()) << "}";
  return s.str();
}

}  // namespace

Quantiles quantilesOf(const std::vector<double>& v) {
  Quantiles q;
  q.count = v.size();
  if (v.empty()) return q;
  q.p50 = quantile(v, 0.5);
  q.p95 = quantile(v, 0.95);
  q.max = *std::max_element(v.begin(), v.end());
  double sum = 0.0;
  for (double x : v) sum += x;
  q.mean = sum / static_cast<double>(v.size());
  return q;
}

Summary summarizeResults(const EvaluationResults& r) {
  Summary s;
  std::vector<VehicleFrameError> ekf, localized, raw, ekf_in_map, raw_in_map, map_error;
  for (const EkfRow& e : r.ekf) {
    ekf.push_back(e.error);
    if (e.map_frame.valid) {
      ekf_in_map.push_back(e.map_frame.in_map);
      map_error.push_back(e.map_frame.map);
    }
    if (std::max(e.sigma_x_m, e.sigma_y_m) <= kLocalizedSigmaM) {
      localized.push_back(e.error);
    } else {
      ++s.ekf_unlocalized;
    }
  }
  s.ekf = summarize(ekf);
  s.ekf_localized = summarize(localized);
  std::vector<double> latency, processing;
  for (const MatchRow& m : r.matches) {
    if (m.outcome != "skipped" || m.total_ms > 0.0) ++s.processed;
    if (m.total_ms > 0.0) processing.push_back(m.total_ms);
    if (m.outcome != "accepted") continue;
    ++s.accepted;
    if (m.fuse == "fused") ++s.fused;
    latency.push_back(m.latency_s);
    if (m.has_pose) {
      raw.push_back(m.error);
      if (m.map_frame.valid) raw_in_map.push_back(m.map_frame.in_map);
      addToIntegrity(m.integrity, std::hypot(m.error.longitudinal_m, m.error.lateral_m),
                     s.integrity_matches);
    }
  }
  finishIntegrity(s.integrity_matches);
  s.raw = summarize(raw);
  s.ekf_in_map = summarize(ekf_in_map);
  s.raw_in_map = summarize(raw_in_map);
  s.map_error = summarize(map_error);
  s.scans = r.info.scans_in_bag > 0 ? r.info.scans_in_bag : r.matches.size() + r.info.dropped_scans;
  s.match_rate_hz = r.info.duration_s > 0.0 ? s.accepted / r.info.duration_s : 0.0;
  s.accepted_share = s.scans > 0 ? static_cast<double>(s.accepted) / s.scans : 0.0;
  s.latency_s = quantilesOf(latency);
  s.processing_ms = quantilesOf(processing);

  s.offset_trials = r.offsets.size();
  if (!r.offsets.empty()) {
    size_t ok = 0, accepted = 0;
    std::vector<double> err, ms;
    double fraction = 0.0;
    for (const OffsetRow& o : r.offsets) {
      const double e = o.has_result ? o.error_m : INFINITY;
      ok += e <= kSuccessM ? 1 : 0;
      accepted += o.accepted ? 1 : 0;
      err.push_back(e);
      ms.push_back(o.search_ms);
      fraction += o.search_fraction;
      if (o.has_result) addToIntegrity(o.integrity, o.error_m, s.integrity_offsets);
    }
    finishIntegrity(s.integrity_offsets);
    s.offset_success = static_cast<double>(ok) / r.offsets.size();
    s.offset_accepted = static_cast<double>(accepted) / r.offsets.size();
    s.offset_error_m = quantilesOf(err);
    s.offset_search_ms = quantilesOf(ms);
    s.offset_mean_fraction = fraction / r.offsets.size();
  }
  if (r.has_obstacles) {
    s.obstacle_precision = r.obstacles.all.precision();
    s.obstacle_recall = r.obstacles.all.recall();
  }
  return s;
}

std::string noDataReason(const EvaluationResults& r, const Summary& s) {
  if (s.ekf.count > 0 || s.raw.count > 0) return {};
  std::ostringstream o;
  o << "no data: no EKF estimate and no accepted match had a ground-truth pose to compare with ("
    << r.ekf.size() << " EKF samples, " << s.accepted << " accepted of " << s.scans
    << " scans); no RMS is reported";
  return o.str();
}

std::string summaryJson(const EvaluationResults& r, const Summary& s) {
  const RunInfo& i = r.info;
  const auto paper = paperRms(i.dataset);
  const auto target = targetRms(i.dataset);
  std::ostringstream o;
  o << "{\n  \"mode\": " << jsonString(i.mode) << ",\n  \"dataset\": " << jsonString(i.dataset)
    << ",\n  \"bag\": " << jsonString(i.bag) << ",\n  \"map\": " << jsonString(i.map)
    << ",\n  \"duration_s\": " << num(i.duration_s, 6) << ",\n  \"wall_s\": " << num(i.wall_s, 6)
    << ",\n  \"map_wall_s\": " << num(i.map_wall_s, 6)
    << ",\n  \"speed_vs_real_time\": " << num(i.wall_s > 0 ? i.duration_s / i.wall_s : NAN)
    << ",\n  \"virtual_latency_s\": " << num(i.virtual_latency_s)
    << ",\n  \"scan_arrival_delay_s\": " << num(i.scan_arrival_delay_s)
    << ",\n  \"no_data\": " << (noDataReason(r, s).empty() ? "false" : "true")
    << ",\n  \"ekf\": " << errorJson(s.ekf)
    << ",\n  \"ekf_localized\": " << errorJson(s.ekf_localized)
    << ",\n  \"ekf_unlocalized_samples\": " << s.ekf_unlocalized
    << ",\n  \"raw_matches\": " << errorJson(s.raw) << ",\n  \"world\": " << jsonString(i.world)
    << ",\n  \"method\": " << jsonString(i.method) << ",\n  \"gps\": " << (i.gps ? "true" : "false")
    << ",\n  \"gnss_fixes\": {\"received\": " << i.gnss_fixes << ", \"fused\": " << i.gnss_fused
    << ", \"gated\": " << i.gnss_gated << ", \"refused\": " << i.gnss_refused
    << ", \"filter_not_running\": " << i.gnss_filter_not_running << "}"
    << ",\n  \"map_poses\": " << jsonString(i.map_poses);
  if (i.map_poses.empty()) {
    o << ",\n  \"ekf_in_map_frame\": null,\n  \"raw_matches_in_map_frame\": null"
      << ",\n  \"map_error\": null";
  } else {
    o << ",\n  \"ekf_in_map_frame\": " << errorJson(s.ekf_in_map)
      << ",\n  \"raw_matches_in_map_frame\": " << errorJson(s.raw_in_map)
      << ",\n  \"map_error\": " << errorJson(s.map_error);
  }
  o << ",\n  \"ekf_inactive_samples\": " << i.ekf_inactive_samples << ",\n  \"scans\": " << s.scans
    << ",\n  \"processed\": " << s.processed << ",\n  \"accepted\": " << s.accepted
    << ",\n  \"fused\": " << (i.mode == "bag" ? std::to_string(s.fused) : std::string("null"))
    << ",\n  \"dropped_scans\": " << i.dropped_scans
    << ",\n  \"match_rate_hz\": " << num(s.match_rate_hz)
    << ",\n  \"accepted_share\": " << num(s.accepted_share)
    << ",\n  \"latency_s\": " << quantilesJson(s.latency_s)
    << ",\n  \"processing_ms\": " << quantilesJson(s.processing_ms)
    << ",\n  \"offsets\": {\"trials\": " << s.offset_trials
    << ", \"success_within_0_5m\": " << num(s.offset_success)
    << ", \"accepted\": " << num(s.offset_accepted)
    << ", \"error_m\": " << quantilesJson(s.offset_error_m)
    << ", \"search_ms\": " << quantilesJson(s.offset_search_ms)
    << ", \"mean_search_fraction\": " << num(s.offset_mean_fraction) << "}"
    << ",\n  \"integrity_matches\": " << integrityJson(s.integrity_matches)
    << ",\n  \"integrity_offsets\": " << integrityJson(s.integrity_offsets);
  if (r.has_obstacles) {
    const ObstacleStats& ob = r.obstacles;
    o << ",\n  \"obstacles\": {\"scans\": " << ob.scans << ", \"all\": " << confusionJson(ob.all)
      << ", \"by_range\": [";
    for (size_t k = 0; k < ob.by_range.size(); ++k) {
      o << (k ? ", " : "") << confusionJson(ob.by_range[k]);
    }
    o << "], \"recall_label_1\": " << num(ob.labelRecall(1))
      << ", \"recall_label_2\": " << num(ob.labelRecall(2)) << "}";
  }
  o << ",\n  \"paper\": {\"rms_longitudinal_m\": " << num(paper[0])
    << ", \"rms_lateral_m\": " << num(paper[1]) << ", \"match_rate_hz\": \"3-4\"}"
    << ",\n  \"target\": {\"rms_longitudinal_m\": " << num(target[0])
    << ", \"rms_lateral_m\": " << num(target[1])
    << ", \"offset_success\": 0.995, \"match_rate_hz\": 10}"
    << ",\n  \"traversal_image\": " << jsonString(i.traversal_image) << ",\n  \"notes\": [";
  for (size_t k = 0; k < i.notes.size(); ++k) o << (k ? ", " : "") << jsonString(i.notes[k]);
  o << "]\n}\n";
  return o.str();
}

std::string summaryMarkdown(const EvaluationResults& r, const Summary& s) {
  const RunInfo& i = r.info;
  const auto paper = paperRms(i.dataset);
  const auto target = targetRms(i.dataset);
  std::ostringstream o;
  o << "## Evaluation: " << i.dataset << (i.world.empty() ? "" : ", " + i.world + " world")
    << (i.method == "height" ? "" : ", " + i.method + " method") << (i.gps ? ", with GPS" : "")
    << " (" << (i.mode == "bag" ? "bag read directly" : "recorded replay") << ")\n\n"
    << "bag `" << i.bag << "`" << (i.map.empty() ? "" : ", map `" + i.map + "`") << "; "
    << fixed(i.duration_s, 1) << " s of driving, evaluated in " << fixed(i.wall_s, 1) << " s wall";
  if (i.wall_s > 0) o << " (" << fixed(i.duration_s / i.wall_s, 2) << "x real time)";
  o << ".\n\n";
  if (i.gps) {
    o << "With GPS (evaluate --gps): " << i.gnss_fixes << " GNSS fixes, " << i.gnss_fused
      << " fused, " << i.gnss_gated << " rejected by the gate, " << i.gnss_refused
      << " refused (no solution), " << i.gnss_filter_not_running
      << " while the filter was not running.\n\n";
  }
  const std::string no_data = noDataReason(r, s);
  if (!no_data.empty())
    o << "**No data**: " << no_data.substr(std::string("no data: ").size()) << ".\n\n";
  o << "| Table I | longitudinal RMS | lateral RMS | heading RMS | samples | match rate |\n"
    << "|---|---|---|---|---|---|\n";
  if (paper[0] > 0) {
    o << "| paper, proposed (" << i.dataset << ") | " << cm(paper[0]) << " | " << cm(paper[1])
      << " | - | - | 3-4 Hz |\n";
  }
  o << "| this run, EKF output | " << cm(s.ekf.rms_longitudinal_m) << " | "
    << cm(s.ekf.rms_lateral_m) << " | " << fixed(s.ekf.rms_yaw_rad * 180.0 / M_PI, 3) << " deg | "
    << s.ekf.count << " | " << fixed(s.match_rate_hz, 2) << " Hz |\n";
  o << "| this run, raw matches | " << cm(s.raw.rms_longitudinal_m) << " | "
    << cm(s.raw.rms_lateral_m) << " | " << fixed(s.raw.rms_yaw_rad * 180.0 / M_PI, 3) << " deg | "
    << s.raw.count << " | " << s.accepted << " accepted of " << s.scans << " scans |\n";
  if (!i.map_poses.empty()) {
    o << "| this run, EKF output against the truth in the map's frame | "
      << cm(s.ekf_in_map.rms_longitudinal_m) << " | " << cm(s.ekf_in_map.rms_lateral_m) << " | "
      << fixed(s.ekf_in_map.rms_yaw_rad * 180.0 / M_PI, 3) << " deg | " << s.ekf_in_map.count
      << " | - |\n";
    o << "| this run, raw matches against the truth in the map's frame | "
      << cm(s.raw_in_map.rms_longitudinal_m) << " | " << cm(s.raw_in_map.rms_lateral_m) << " | "
      << fixed(s.raw_in_map.rms_yaw_rad * 180.0 / M_PI, 3) << " deg | " << s.raw_in_map.count
      << " | - |\n";
    o << "| the map's own error along the drive (its poses against their truth) | "
      << cm(s.map_error.rms_longitudinal_m) << " | " << cm(s.map_error.rms_lateral_m) << " | "
      << fixed(s.map_error.rms_yaw_rad * 180.0 / M_PI, 3) << " deg | " << s.map_error.count
      << " | - |\n";
  }
  if (target[0] > 0) {
    o << "| target | " << cm(target[0]) << " | " << cm(target[1]) << " | - | - | 10 Hz |\n";
  }
  if (!i.map_poses.empty()) {
    o << "\nThe map was built from inexact poses (`" << i.map_poses
      << "`): \"in the map's frame\" compares with the truth moved by the map's own error where "
         "the vehicle is (the localization's own error); the first rows compare with the exact "
         "truth (docs/evaluation.md).\n";
  }
  if (s.ekf_unlocalized > 0) {
    o << "\nEKF samples with a reported sigma above " << fixed(kLocalizedSigmaM, 1)
      << " m (not localized yet): " << s.ekf_unlocalized << "; without them the EKF RMS is "
      << cm(s.ekf_localized.rms_longitudinal_m) << " longitudinal, "
      << cm(s.ekf_localized.rms_lateral_m) << " lateral.\n";
  }
  o << "\nEKF: p95 planar error " << cm(s.ekf.p95_planar_m) << ", max " << cm(s.ekf.max_planar_m)
    << "; raw matches: p95 " << cm(s.raw.p95_planar_m) << ", max " << cm(s.raw.max_planar_m)
    << ".\n\n";
  o << "Matching: " << s.processed << " scans processed, " << s.accepted << " accepted ("
    << pct(s.accepted_share) << " of " << s.scans << " scans), "
    << (i.mode == "bag" ? std::to_string(s.fused) + " fused by the EKF, " : std::string())
    << i.dropped_scans << " dropped as stale; latency (stamp to result) "
    << "median " << fixed(s.latency_s.p50 * 1000.0, 0) << " ms, p95 "
    << fixed(s.latency_s.p95 * 1000.0, 0) << " ms";
  if (i.mode == "bag") {
    o << " (virtual: "
      << (i.virtual_latency_s >= 0 ? fixed(i.virtual_latency_s * 1000.0, 0) + " ms fixed"
                                   : std::string("measured"))
      << " processing + " << fixed(i.scan_arrival_delay_s * 1000.0, 0) << " ms arrival)";
  }
  o << "; measured processing per scan median " << fixed(s.processing_ms.p50, 0) << " ms, p95 "
    << fixed(s.processing_ms.p95, 0) << " ms, max " << fixed(s.processing_ms.max, 0) << " ms.\n\n";
  if (s.offset_trials > 0) {
    o << "Fig. 8 (random offsets): " << s.offset_trials << " registrations, "
      << pct(s.offset_success) << " within 0.5 m (target 99.5%), " << pct(s.offset_accepted)
      << " accepted; error median " << cm(s.offset_error_m.p50) << ", p95 "
      << cm(s.offset_error_m.p95) << "; search median " << fixed(s.offset_search_ms.p50, 0)
      << " ms, " << fixed(s.offset_mean_fraction * 100.0, 2)
      << "% of the exhaustive poses scored.\n\n";
  }
  o << integrityMarkdown(s.integrity_matches, "accepted drive matches");
  if (s.offset_trials > 0) o << integrityMarkdown(s.integrity_offsets, "Fig. 8 registrations");
  if (r.has_obstacles) {
    const ObstacleStats& ob = r.obstacles;
    o << "Obstacles (label != 0 is an obstacle; " << ob.scans << " accepted scans): precision "
      << pct(s.obstacle_precision) << ", recall " << pct(s.obstacle_recall) << "; by range";
    const char* bins[4] = {"0-20 m", "20-40 m", "40-60 m", ">60 m"};
    for (size_t k = 0; k < 4; ++k) {
      o << (k ? ", " : " ") << bins[k] << " P " << pct(ob.by_range[k].precision()) << " R "
        << pct(ob.by_range[k].recall());
    }
    o << "; recall of label 1 (dynamic/changed) " << pct(ob.labelRecall(1)) << ", label 2 (snow) "
      << pct(ob.labelRecall(2)) << ".\n\n";
  }
  for (const std::string& n : i.notes) o << "Note: " << n << "\n\n";
  return o.str();
}

}  // namespace eval
}  // namespace gmm_localization
