#include "gmm_localization/core/matching/reflectivity_scan.h"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace gmm_localization {

PointList reflectivityPoints(const PointList& base_points, const std::vector<float>& intensity,
                             double roll_rad, double pitch_rad,
                             const ReflectivityLayerOptions& options) {
  PointList out;
  if (intensity.size() != base_points.size()) return out;
  // The same levelling as filterScan: base_link rotated by pitch and roll, no yaw.
  const Eigen::Matrix3f level = (Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix()
                                    .cast<float>();
  out.reserve(base_points.size() / 2);
  for (size_t i = 0; i < base_points.size(); ++i) {
    if (!base_points[i].allFinite() || !std::isfinite(intensity[i])) continue;
    const Eigen::Vector3f p = level * base_points[i];
    if (!options.isGround(p.z(), std::hypot(p.x(), p.y()))) continue;
    out.emplace_back(p.x(), p.y(), options.value(intensity[i]));
  }
  return out;
}

RegistrationOptions reflectivityRegistrationOptions(const RegistrationOptions& height) {
  RegistrationOptions o = height;
  o.z_search_m = 0.0;
  o.hill_climb.max_z_m = 0.0;
  o.hill_climb.max_roll_pitch_rad = 0.0;
  o.classify_obstacles = false;
  // Values span 0..5.1 m at the default scale (intensity 0..255); the points are ground.
  o.filter.min_height_m = -1.0;
  o.filter.max_height_m = 1000.0;
  o.filter.ground_share = 1.0;
  // The global search's score floor was measured on the height likelihood: none here.
  o.global.min_score_per_point = -std::numeric_limits<double>::infinity();
  return o;
}

}  // namespace gmm_localization
