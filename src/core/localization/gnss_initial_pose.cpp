// GNSS initial pose: fixes and headings -> a map-frame pose (gnss_initial_pose.h).
#include "gmm_localization/core/localization/gnss_initial_pose.h"

#include "gmm_localization/core/localization/gnss_position.h"

#include <cstdio>
#include <utility>

#include <Eigen/Dense>

namespace gmm_localization {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

double wrapToPi(double a) { return std::atan2(std::sin(a), std::cos(a)); }

std::string format(const char* fmt, double a, double b) {
  char s[200];
  std::snprintf(s, sizeof s, fmt, a, b);
  return s;
}

}  // namespace

std::string GnssInitialPoseOptions::validate() const {
  if (!positive(max_horizontal_sigma_m)) return "max_horizontal_sigma_m must be > 0";
  if (!positive(unknown_sigma_m)) return "unknown_sigma_m must be > 0";
  if (!(std::isfinite(min_sigma_m) && min_sigma_m >= 0.0)) return "min_sigma_m must be >= 0";
  if (!positive(max_heading_age_s)) return "max_heading_age_s must be > 0";
  if (!positive(default_heading_sigma_rad)) return "default_heading_sigma_rad must be > 0";
  if (!positive(course_min_distance_m)) return "course_min_distance_m must be > 0";
  if (!positive(course_max_gap_s)) return "course_max_gap_s must be > 0";
  if (!positive(course_sigma_rad)) return "course_sigma_rad must be > 0";
  if (!positive(max_distance_from_origin_m)) return "max_distance_from_origin_m must be > 0";
  if (!antenna_in_base.allFinite()) return "antenna_in_base must be finite";
  return {};
}

GnssInitialPose::GnssInitialPose(GnssInitialPoseOptions options) : options_(std::move(options)) {}

void GnssInitialPose::reset() {
  have_heading_ = false;
  track_.clear();
}

bool GnssInitialPose::addHeading(const GnssHeading& heading) {
  if (!std::isfinite(heading.stamp_s) || !std::isfinite(heading.enu_yaw_rad)) return false;
  if (!(std::isnan(heading.sigma_rad) || heading.sigma_rad >= 0.0)) return false;
  heading_ = heading;
  have_heading_ = true;
  return true;
}

Result<GnssPoseEstimate> GnssInitialPose::addFix(const Georeference& geo, const GnssFix& fix) {
  using R = Result<GnssPoseEstimate>;
  const GnssInitialPoseOptions& o = options_;
  auto placed = gnssFixInMap(geo, fix, o.unknown_sigma_m, o.max_distance_from_origin_m);
  if (!placed) return R::failure(placed.error());
  const MapPosition* in_map = &placed->antenna;
  const double g = in_map->convergence_rad;
  Eigen::Matrix2d cov_xy = placed->cov_xy;
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov_xy).eigenvalues()(1);
  if (!(std::sqrt(std::max(largest, 0.0)) <= o.max_horizontal_sigma_m)) {
    return R::failure(
        format("fix too coarse: horizontal sigma %.1f m (max_horizontal_sigma_m %.1f)",
               std::sqrt(std::max(largest, 0.0)), o.max_horizontal_sigma_m));
  }
  cov_xy += Eigen::Matrix2d::Identity() * o.min_sigma_m * o.min_sigma_m;

  // The antenna track for the course over ground (oldest first, within course_max_gap_s).
  while (!track_.empty() && (fix.stamp_s - track_.front().stamp_s > o.course_max_gap_s ||
                             fix.stamp_s < track_.back().stamp_s)) {
    track_.pop_front();
  }
  track_.push_back({fix.stamp_s, in_map->x_m, in_map->y_m});

  GnssPoseEstimate e;
  e.stamp_s = fix.stamp_s;
  double yaw_sigma = 0.0;
  if (have_heading_ && std::abs(fix.stamp_s - heading_.stamp_s) <= o.max_heading_age_s) {
    e.yaw_rad = wrapToPi(heading_.enu_yaw_rad + g);
    yaw_sigma = std::isnan(heading_.sigma_rad) || heading_.sigma_rad <= 0.0
                    ? o.default_heading_sigma_rad
                    : heading_.sigma_rad;
    e.heading_source = "heading topic";
  } else {
    const Track& first = track_.front();
    const double dx = in_map->x_m - first.x_m, dy = in_map->y_m - first.y_m;
    const double moved = std::hypot(dx, dy);
    if (moved < o.course_min_distance_m) {
      return R::failure(format(
          "waiting for a heading: no heading message within max_heading_age_s, and the antenna "
          "moved %.1f m of the %.1f m (course_min_distance_m) that give a course over ground",
          moved, o.course_min_distance_m));
    }
    e.yaw_rad = std::atan2(dy, dx);
    // Position noise of both ends across the baseline.
    const double position_sigma = std::sqrt(2.0 * cov_xy.trace() / 2.0);
    yaw_sigma = std::hypot(o.course_sigma_rad, position_sigma / moved);
    e.heading_source = "course over ground";
  }
  const double c = std::cos(e.yaw_rad), s = std::sin(e.yaw_rad);
  const Eigen::Vector3d& lever = o.antenna_in_base;
  e.x_m = in_map->x_m - (c * lever.x() - s * lever.y());
  e.y_m = in_map->y_m - (s * lever.x() + c * lever.y());
  e.z_m = in_map->z_m - lever.z();
  e.cov_xy_yaw.setZero();
  e.cov_xy_yaw.topLeftCorner<2, 2>() = cov_xy;
  e.cov_xy_yaw(2, 2) = yaw_sigma * yaw_sigma;
  e.z_sigma_m = std::isfinite(fix.up_var_m2) && fix.up_var_m2 >= 0.0
                    ? std::sqrt(fix.up_var_m2 + o.min_sigma_m * o.min_sigma_m)
                    : NAN;
  return e;
}

}  // namespace gmm_localization
