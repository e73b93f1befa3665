#include "gmm_localization/ros/matcher_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

bool finite(const Pose6& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
         std::isfinite(p.pitch) && std::isfinite(p.yaw);
}

/// Finite number or 0 (status fields are never NaN).
double safe(double v) { return std::isfinite(v) ? v : 0.0; }

void fillCovariance(const Matrix6d& c, boost::array<double, 36>& out) {
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) out[i * 6 + j] = c(i, j);
  }
}

bool hasLabels(const MatchReport& r) {
  return r.has_result && r.result.obstacles.label.size() == r.points.size() && !r.points.empty();
}

}  // namespace

void toStatusMsg(const MatchReport& r, const std::string& map_frame, double latency_s,
                 uint32_t dropped, MatchStatus& msg) {
  msg.header.frame_id = map_frame;
  msg.accepted = r.accepted();
  msg.reason = r.reason;
  msg.prior_source = priorSourceName(r.prior.source);
  msg.prior_mode = priorModeName(r.mode_after);
  msg.window_x_m = r.prior.valid() ? safe(r.prior.pose.x) : 0.0;
  msg.window_y_m = r.prior.valid() ? safe(r.prior.pose.y) : 0.0;
  msg.window_half_x_m = safe(r.window.half_x_m);
  msg.window_half_y_m = safe(r.window.half_y_m);
  msg.window_half_heading_rad = safe(r.window.half_heading_rad);
  msg.input_points = static_cast<uint32_t>(r.input_points);
  msg.dropped_nonfinite = static_cast<uint32_t>(r.dropped_nonfinite);
  msg.search_points = static_cast<uint32_t>(r.search_points);
  msg.deskewed = r.deskewed;
  msg.point_times = r.time_source;
  msg.deskew_note = r.deskewed ? std::string() : r.deskew_note;
  msg.search_evaluations =
      r.has_result ? static_cast<uint64_t>(r.result.search.stats.evaluations) : 0;
  msg.search_fraction = r.has_result ? safe(r.result.search.stats.fraction()) : 0.0;
  msg.log_likelihood_per_point = r.has_result ? safe(r.result.log_likelihood_per_point) : 0.0;
  msg.map_coverage = r.has_result ? safe(r.result.map_coverage) : 0.0;
  msg.z_offset_m = r.has_result ? safe(r.result.z_offset_m) : 0.0;
  msg.correction_xy_m = safe(r.correction_xy_m);
  msg.correction_yaw_rad = safe(r.correction_yaw_rad);
  const MatchCertificate& cert = r.result.certificate;
  msg.certified = r.has_result && cert.certified;
  msg.certificate_failure = r.has_result ? certificateFailureName(cert.failure) : "";
  msg.separation_per_point = r.has_result ? safe(cert.separation_per_point) : 0.0;
  msg.separation_exact = r.has_result && cert.separation_exact;
  msg.protection_xy_m = r.has_result ? safe(r.result.protection_xy_m) : 0.0;
  msg.protection_heading_rad = r.has_result ? safe(r.result.protection_heading_rad) : 0.0;
  msg.certificate_evaluations = r.has_result ? static_cast<uint64_t>(cert.evaluations) : 0;
  // A window searched over heading intervals is the global search's, also when the search
  // stopped at its budget or was cancelled, which leaves no result.
  const bool global_result = r.has_result && r.result.global;
  msg.global_search = global_result || (r.global_window && r.outcome != MatchOutcome::kSkipped);
  msg.global_certified = global_result && r.result.global_certificate.certified;
  msg.global_separation_per_point =
      global_result ? safe(r.result.global_certificate.separation_per_point) : 0.0;
  msg.certificate_ms = 1e3 * safe(r.timing.certificate_s);
  msg.filter_ms = 1e3 * safe(r.timing.filter_s);
  msg.search_ms = 1e3 * safe(r.timing.search_s);
  msg.refine_ms = 1e3 * safe(r.timing.refine_s + r.timing.covariance_s);
  msg.total_ms = 1e3 * safe(r.total_s);
  msg.latency_ms = 1e3 * safe(latency_s);
  msg.obstacle_points = r.has_result ? static_cast<uint32_t>(r.result.obstacles.obstacles) : 0;
  msg.dropped_scans = dropped;
  Pose6 shown;
  if (r.accepted() && finite(r.pose)) {
    shown = r.pose;
    fillCovariance(r.covariance.allFinite() ? r.covariance : Matrix6d::Zero(), msg.pose.covariance);
  } else {
    if (r.has_result && finite(r.result.pose)) {
      shown = r.result.pose;
    } else if (r.prior.valid() && finite(r.prior.pose)) {
      shown = r.prior.pose;
    }
    msg.pose.covariance.fill(0.0);
  }
  msg.pose.pose = toMsg(shown);
}

bool toMatchPoseMsg(const MatchReport& r, const std::string& map_frame,
                    geometry_msgs::PoseWithCovarianceStamped& msg) {
  if (!r.accepted() || !finite(r.pose) || !r.covariance.allFinite()) return false;
  msg.header.frame_id = map_frame;
  msg.pose.pose = toMsg(r.pose);
  fillCovariance(r.covariance, msg.pose.covariance);
  return isFinite(msg.pose.pose);
}

bool toObstaclesCloud(const MatchReport& r, bool in_map, sensor_msgs::PointCloud2& msg) {
  if (!hasLabels(r)) return false;
  const Eigen::Isometry3f T = toIsometry(r.result.pose).cast<float>();
  const ObstacleLabels& labels = r.result.obstacles;
  sensor_msgs::PointCloud2Modifier mod(msg);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(labels.obstacles);
  sensor_msgs::PointCloud2Iterator<float> x(msg, "x"), y(msg, "y"), z(msg, "z");
  size_t n = 0;
  for (size_t i = 0; i < r.points.size() && n < labels.obstacles; ++i) {
    if (labels.label[i] != PointClass::kObstacle || !r.points[i].allFinite()) continue;
    const Eigen::Vector3f p = in_map ? Eigen::Vector3f(T * r.points[i]) : r.points[i];
    *x = p.x(), *y = p.y(), *z = p.z();
    ++x, ++y, ++z, ++n;
  }
  mod.resize(n);
  msg.height = 1;
  msg.is_dense = true;
  return true;
}

bool toClassifiedCloud(const MatchReport& r, double max_mahalanobis,
                       sensor_msgs::PointCloud2& msg) {
  if (!hasLabels(r)) return false;
  const Eigen::Isometry3f T = toIsometry(r.result.pose).cast<float>();
  const ObstacleLabels& labels = r.result.obstacles;
  sensor_msgs::PointCloud2Modifier mod(msg);
  mod.setPointCloud2Fields(
      5, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z", 1,
      sensor_msgs::PointField::FLOAT32, "mahalanobis", 1, sensor_msgs::PointField::FLOAT32, "class",
      1, sensor_msgs::PointField::UINT8);
  mod.resize(r.points.size());
  sensor_msgs::PointCloud2Iterator<float> x(msg, "x"), y(msg, "y"), z(msg, "z"),
      m(msg, "mahalanobis");
  sensor_msgs::PointCloud2Iterator<uint8_t> c(msg, "class");
  const float cap = static_cast<float>(max_mahalanobis);
  size_t n = 0;
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (!r.points[i].allFinite()) continue;
    const Eigen::Vector3f p = T * r.points[i];
    const float d = labels.mahalanobis.size() == r.points.size() ? labels.mahalanobis[i] : cap;
    *x = p.x(), *y = p.y(), *z = p.z();
    *m = std::isfinite(d) ? std::min(d, cap) : cap;
    *c = static_cast<uint8_t>(labels.label[i]);
    ++x, ++y, ++z, ++m, ++c, ++n;
  }
  mod.resize(n);
  msg.height = 1;
  msg.is_dense = true;
  return true;
}

bool toTraversalImage(const MatchReport& r, const TraversalImageOptions& options,
                      sensor_msgs::Image& msg) {
  if (!r.has_result || r.traversal.empty()) return false;
  const TraversalImage img = renderTraversal(
      r.traversal, r.search_window, r.result.search.stats.top_layer, r.result.search, options);
  if (img.rgb.empty()) return false;
  msg.height = static_cast<uint32_t>(img.height);
  msg.width = static_cast<uint32_t>(img.width);
  msg.encoding = sensor_msgs::image_encodings::RGB8;
  msg.is_bigendian = 0;
  msg.step = static_cast<uint32_t>(3 * img.width);
  msg.data = img.rgb;
  return true;
}

}  // namespace node
}  // namespace gmm_localization
