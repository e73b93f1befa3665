#pragma once
// A GNSS fix in the map frame: the shared placing of a receiver fix through the map's
// georeference (georeference.h: UTM grid, shifted) with its horizontal covariance turned from
// ENU into the grid by the meridian convergence. Used by the GNSS initial pose
// (gnss_initial_pose.h) and, as a position measurement, by the EKF's optional GNSS input
// (LocalizationFilter::addGnss; the paper's reflectivity baseline ran "with GPS").
//
// The measurement: base_link = antenna - Rz(yaw) * antenna_in_base (yaw: the filter's current
// heading; roll and pitch neglected), covariance = the fix's (unknown_sigma_m when it reports
// none) + min_sigma_m^2 (the map's own georeference error). The EKF models a receiver's
// slowly varying bias (metres, minutes) as a state (EkfOptions::estimate_gnss_bias,
// ekf_state.h): the fix reads the position plus that bias. The fix's covariance is taken as its
// white part although receivers usually report their whole error: conservative, the bias is
// then counted twice.
// Units: metres, radians, seconds.

#include <cmath>
#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/localization/gnss_initial_pose.h"
#include "gmm_localization/core/map/georeference.h"

namespace gmm_localization {

/// A fix placed in the map frame.
struct GnssFixInMap {
  MapPosition antenna;     ///< the antenna in map, with the meridian convergence
  Eigen::Matrix2d cov_xy;  ///< horizontal covariance in the map (grid) axes [m^2]
  double up_var_m2 = NAN;  ///< NaN when the fix gives none
  bool covariance_known = false;
};

/// Fails for a map without a grid, a fix without a solution, a non-finite stamp, a position
/// that does not convert (or is farther than max_distance_m from the map origin). A fix without
/// a usable covariance gets unknown_sigma_m per horizontal axis.
Result<GnssFixInMap> gnssFixInMap(const Georeference& georeference, const GnssFix& fix,
                                  double unknown_sigma_m, double max_distance_m);

struct GnssPositionOptions {
  double unknown_sigma_m = 3.0;          ///< horizontal sigma of a fix without covariance
  double min_sigma_m = 0.0;              ///< added in quadrature (georeference error)
  double max_horizontal_sigma_m = 10.0;  ///< coarser fixes are refused
  bool use_z = false;                    ///< fuse the altitude too (needs the fix's up variance)
  double max_distance_from_origin_m = 1e5;
  Eigen::Vector3d antenna_in_base = Eigen::Vector3d::Zero();  ///< lever arm, base_link frame

  /// Empty when valid, else which field is wrong.
  std::string validate() const;
};

/// The EKF position measurement of a fix, base_link's position given the heading base_yaw_rad.
Result<PositionMeasurement> gnssPositionMeasurement(const Georeference& georeference,
                                                    const GnssFix& fix,
                                                    const GnssPositionOptions& options,
                                                    double base_yaw_rad);

}  // namespace gmm_localization
