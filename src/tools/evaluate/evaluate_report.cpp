// CSV files, summary.json and summary.md of an evaluation (evaluate_results.h).
#include <sys/stat.h>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "evaluate/evaluate_results.h"
#include "evaluate/evaluate_summary.h"

namespace gmm_localization {
namespace eval {
namespace {

std::ofstream openFile(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << std::setprecision(16);
  return f;
}

std::string csvText(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string integrityColumns(const IntegrityFields& f) {
  std::ostringstream s;
  s << std::setprecision(16) << (f.certified ? 1 : 0) << ',' << f.failure << ','
    << f.protection_xy_m << ',' << f.protection_heading_rad << ',' << f.separation_per_point << ',';
  if (std::isfinite(f.truth_deficit_per_point)) s << f.truth_deficit_per_point;  // empty: no truth
  s << ',' << f.certificate_ms;
  return s.str();
}

/// The map-frame columns (empty without --map-poses or where the map holds nothing).
std::string mapFrameColumns(const MapFrameErrors& m) {
  if (!m.valid) return ",,,";
  std::ostringstream s;
  s << std::setprecision(16) << m.map.longitudinal_m << ',' << m.map.lateral_m << ','
    << m.in_map.longitudinal_m << ',' << m.in_map.lateral_m;
  return s.str();
}
constexpr const char* kMapFrameHeader =
    "map_longitudinal_m,map_lateral_m,in_map_longitudinal_m,in_map_lateral_m";

void writeEkf(const std::vector<EkfRow>& rows, const std::string& path) {
  std::ofstream f = openFile(path);
  f << "t,x,y,z,yaw,gt_x,gt_y,gt_z,gt_yaw,longitudinal_m,lateral_m,yaw_err_rad,sigma_x_m,"
       "sigma_y_m,sigma_yaw_rad,"
    << kMapFrameHeader << ",twist_scale,gnss_bias_x_m,gnss_bias_y_m\n";
  for (const EkfRow& r : rows) {
    f << r.t << ',' << r.estimate.x << ',' << r.estimate.y << ',' << r.estimate.z << ','
      << r.estimate.yaw << ',' << r.truth.x << ',' << r.truth.y << ',' << r.truth.z << ','
      << r.truth.yaw << ',' << r.error.longitudinal_m << ',' << r.error.lateral_m << ','
      << r.error.yaw_rad << ',' << r.sigma_x_m << ',' << r.sigma_y_m << ',' << r.sigma_yaw_rad
      << ',' << mapFrameColumns(r.map_frame) << ',' << r.twist_scale << ',' << r.gnss_bias_x_m
      << ',' << r.gnss_bias_y_m << '\n';
  }
}

void writeMatches(const std::vector<MatchRow>& rows, const std::string& path) {
  std::ofstream f = openFile(path);
  f << "stamp,outcome,reason,prior_source,wide,window_half_x_m,window_half_heading_rad,"
       "input_points,search_points,evaluations,search_fraction,log_likelihood_per_point,"
       "map_coverage,filter_ms,search_ms,refine_ms,total_ms,latency_s,dropped_before,fuse,"
       "has_pose,x,y,yaw,longitudinal_m,lateral_m,yaw_err_rad,obst_tp,obst_fp,obst_fn,obst_tn,"
       "certified,certificate_failure,protection_xy_m,protection_heading_rad,"
       "separation_per_point,truth_deficit_per_point,certificate_ms,"
    << kMapFrameHeader << '\n';
  for (const MatchRow& r : rows) {
    f << r.stamp_s << ',' << r.outcome << ',' << csvText(r.reason) << ',' << r.prior_source << ','
      << (r.wide ? 1 : 0) << ',' << r.window_half_x_m << ',' << r.window_half_heading_rad << ','
      << r.input_points << ',' << r.search_points << ',' << r.evaluations << ','
      << r.search_fraction << ',' << r.log_likelihood_per_point << ',' << r.map_coverage << ','
      << r.filter_ms << ',' << r.search_ms << ',' << r.refine_ms << ',' << r.total_ms << ','
      << r.latency_s << ',' << r.dropped_before << ',' << r.fuse << ',' << (r.has_pose ? 1 : 0)
      << ',' << r.pose.x << ',' << r.pose.y << ',' << r.pose.yaw << ',' << r.error.longitudinal_m
      << ',' << r.error.lateral_m << ',' << r.error.yaw_rad << ',' << r.obstacles.tp << ','
      << r.obstacles.fp << ',' << r.obstacles.fn << ',' << r.obstacles.tn << ','
      << integrityColumns(r.integrity) << ',' << mapFrameColumns(r.map_frame) << '\n';
  }
}

void writeOffsets(const std::vector<OffsetRow>& rows, const std::string& path) {
  std::ofstream f = openFile(path);
  f << "stamp,dx_m,dy_m,offset_m,dyaw_rad,has_result,accepted,error_m,error_yaw_rad,"
       "evaluations,search_fraction,search_ms,total_ms,reason,certified,certificate_failure,"
       "protection_xy_m,protection_heading_rad,separation_per_point,truth_deficit_per_point,"
       "certificate_ms\n";
  for (const OffsetRow& r : rows) {
    f << r.stamp_s << ',' << r.offset.dx_m << ',' << r.offset.dy_m << ',' << r.offset.distance_m()
      << ',' << r.offset.dyaw_rad << ',' << (r.has_result ? 1 : 0) << ',' << (r.accepted ? 1 : 0)
      << ',' << r.error_m << ',' << r.error_yaw_rad << ',' << r.evaluations << ','
      << r.search_fraction << ',' << r.search_ms << ',' << r.total_ms << ',' << csvText(r.reason)
      << ',' << integrityColumns(r.integrity) << '\n';
  }
}

}  // namespace

std::array<double, 2> paperRms(const std::string& dataset) {
  if (dataset == "downtown") return {0.155, 0.103};
  if (dataset == "snowy") return {0.180, 0.094};
  return {0.0, 0.0};
}

std::string writeResults(const EvaluationResults& results, const std::string& directory) {
  ::mkdir(directory.c_str(), 0755);
  struct stat st;
  if (::stat(directory.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    throw std::runtime_error("cannot create the output directory " + directory);
  }
  writeEkf(results.ekf, directory + "/ekf.csv");
  writeMatches(results.matches, directory + "/matches.csv");
  if (!results.offsets.empty()) writeOffsets(results.offsets, directory + "/offsets.csv");
  const Summary summary = summarizeResults(results);
  {
    std::ofstream f = openFile(directory + "/summary.json");
    f << summaryJson(results, summary);
  }
  const std::string md = summaryMarkdown(results, summary);
  std::ofstream f = openFile(directory + "/summary.md");
  f << md;
  return md;
}

}  // namespace eval
}  // namespace gmm_localization
