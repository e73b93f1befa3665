// A GNSS fix in the map frame, and the EKF position measurement made of it (gnss_position.h).
#include "gmm_localization/core/localization/gnss_position.h"

#include <cstdio>

#include <Eigen/Dense>

namespace gmm_localization {

Result<GnssFixInMap> gnssFixInMap(const Georeference& geo, const GnssFix& fix,
                                  double unknown_sigma_m, double max_distance_m) {
  using R = Result<GnssFixInMap>;
  if (!geo.hasGrid()) {
    return R::failure(geo.present ? "the map's georeference names no UTM zone (text only: '" +
                                        geo.datum + "')"
                                  : "the map has no georeference");
  }
  if (!fix.has_solution) return R::failure("the receiver reports no fix");
  if (!std::isfinite(fix.stamp_s)) return R::failure("fix stamp not finite");
  auto in_map = geodeticToMap(geo, fix.position, max_distance_m);
  if (!in_map) return R::failure("fix refused: " + in_map.error());
  GnssFixInMap out;
  out.antenna = *in_map;
  // Horizontal covariance: ENU -> grid (rotation by the convergence).
  Eigen::Matrix2d cov_en;
  out.covariance_known = std::isfinite(fix.east_var_m2) && std::isfinite(fix.north_var_m2) &&
                         fix.east_var_m2 >= 0.0 && fix.north_var_m2 >= 0.0 &&
                         std::isfinite(fix.east_north_cov_m2);
  if (out.covariance_known) {
    cov_en << fix.east_var_m2, fix.east_north_cov_m2, fix.east_north_cov_m2, fix.north_var_m2;
  } else {
    cov_en = Eigen::Matrix2d::Identity() * unknown_sigma_m * unknown_sigma_m;
  }
  const double g = in_map->convergence_rad;
  Eigen::Matrix2d rot;
  rot << std::cos(g), -std::sin(g), std::sin(g), std::cos(g);
  out.cov_xy = rot * cov_en * rot.transpose();
  out.up_var_m2 = std::isfinite(fix.up_var_m2) && fix.up_var_m2 >= 0.0 ? fix.up_var_m2 : NAN;
  return out;
}

std::string GnssPositionOptions::validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(unknown_sigma_m)) return "unknown_sigma_m must be > 0";
  if (!(std::isfinite(min_sigma_m) && min_sigma_m >= 0.0)) return "min_sigma_m must be >= 0";
  if (!positive(max_horizontal_sigma_m)) return "max_horizontal_sigma_m must be > 0";
  if (!positive(max_distance_from_origin_m)) return "max_distance_from_origin_m must be > 0";
  if (!antenna_in_base.allFinite()) return "antenna_in_base must be finite";
  return {};
}

Result<PositionMeasurement> gnssPositionMeasurement(const Georeference& geo, const GnssFix& fix,
                                                    const GnssPositionOptions& o,
                                                    double base_yaw_rad) {
  using R = Result<PositionMeasurement>;
  auto in_map = gnssFixInMap(geo, fix, o.unknown_sigma_m, o.max_distance_from_origin_m);
  if (!in_map) return R::failure(in_map.error());
  const double largest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(in_map->cov_xy).eigenvalues()(1);
  if (!(std::sqrt(std::max(largest, 0.0)) <= o.max_horizontal_sigma_m)) {
    char s[160];
    std::snprintf(s, sizeof s,
                  "fix too coarse: horizontal sigma %.1f m (max_horizontal_sigma_m %.1f)",
                  std::sqrt(std::max(largest, 0.0)), o.max_horizontal_sigma_m);
    return R::failure(s);
  }
  if (!std::isfinite(base_yaw_rad)) return R::failure("the heading is not finite");
  if (o.use_z && std::isnan(in_map->up_var_m2)) {
    return R::failure("use_z is set but the fix gives no altitude variance");
  }
  const double c = std::cos(base_yaw_rad), s = std::sin(base_yaw_rad);
  const Eigen::Vector3d& lever = o.antenna_in_base;
  const MapPosition& a = in_map->antenna;
  PositionMeasurement m;
  m.stamp_s = fix.stamp_s;
  m.position_m = Eigen::Vector3d(a.x_m - (c * lever.x() - s * lever.y()),
                                 a.y_m - (s * lever.x() + c * lever.y()), a.z_m - lever.z());
  const double floor = o.min_sigma_m * o.min_sigma_m;
  m.covariance.setZero();
  m.covariance.topLeftCorner<2, 2>() = in_map->cov_xy + Eigen::Matrix2d::Identity() * floor;
  m.covariance(2, 2) = o.use_z ? in_map->up_var_m2 + floor : 1.0;
  m.use_z = o.use_z;
  return m;
}

}  // namespace gmm_localization
