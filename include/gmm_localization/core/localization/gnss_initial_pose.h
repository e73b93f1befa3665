#pragma once
// A first pose from GNSS: turns receiver fixes (WGS84 latitude, longitude, altitude) and a heading
// into a map-frame pose with its covariance, for the matcher's and the EKF's initial pose, so a
// vehicle starts without a person clicking in rviz (the GNSS initializer nodelet feeds it).
//
// Position: the fix in the map frame of the map's georeference (georeference.h: UTM grid,
// shifted), then the antenna's lever arm (antenna_in_base, from TF) removed with the heading:
// base = antenna - Rz(yaw) * lever (roll and pitch neglected: a 1 m high antenna on a 3 deg
// slope moves 5 cm). Its horizontal covariance is the fix's ENU block turned into the grid by the
// meridian convergence, floored at min_sigma_m; a fix without covariance is taken as
// unknown_sigma_m. Fixes without a solution (status NO_FIX) or worse than max_horizontal_sigma_m
// are refused.
//
// Heading, the first available of:
//   1. a heading measurement (an INS/dual-antenna receiver's ENU yaw, REP-103/REP-145, e.g. the
//      orientation of its sensor_msgs/Imu) at most max_heading_age_s older than the fix; the map
//      yaw is the ENU yaw plus the meridian convergence;
//   2. the course over ground: the direction from an earlier fix to this one once the antenna has
//      moved course_min_distance_m within course_max_gap_s. This assumes the vehicle drives
//      forwards (reversing gives the opposite heading) and fairly straight; its sigma is
//      course_sigma_rad plus the fixes' position noise over the distance.
// Until a heading is known addFix fails with a reason that says what it waits for.
//
// Units: metres, radians, seconds. Frames: map (REP-105), ENU for the receiver's heading.

#include <cmath>
#include <deque>
#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/georeference.h"

namespace gmm_localization {

struct GnssFix {
  double stamp_s = 0.0;
  GeodeticPosition position;
  bool has_solution = true;  ///< false: the receiver reports no fix
  /// Variances of the antenna position east, north, up [m^2]; NaN when the receiver gives none.
  double east_var_m2 = NAN, north_var_m2 = NAN, up_var_m2 = NAN;
  double east_north_cov_m2 = 0.0;
};

struct GnssHeading {
  double stamp_s = 0.0;
  double enu_yaw_rad = 0.0;  ///< heading of base_link, counter-clockwise from true east
  double sigma_rad = NAN;    ///< NaN: unknown (default_heading_sigma_rad is used)
};

struct GnssInitialPoseOptions {
  double max_horizontal_sigma_m = 10.0;  ///< fixes worse than this are refused
  double unknown_sigma_m = 3.0;          ///< horizontal sigma of a fix without covariance
  double min_sigma_m = 0.3;              ///< floor of the horizontal sigma (map georeference error)
  double max_heading_age_s = 1.0;
  double default_heading_sigma_rad = 0.05;
  double course_min_distance_m = 8.0;
  double course_max_gap_s = 10.0;
  double course_sigma_rad = 0.1;
  double max_distance_from_origin_m = 1e5;  ///< refuse fixes farther from the map origin
  Eigen::Vector3d antenna_in_base = Eigen::Vector3d::Zero();  ///< lever arm, base_link frame

  /// Empty when valid, else which field is wrong.
  std::string validate() const;
};

struct GnssPoseEstimate {
  double stamp_s = 0.0;
  double x_m = 0.0, y_m = 0.0, z_m = 0.0, yaw_rad = 0.0;
  /// Covariance of (x, y, yaw) [m^2, m^2 rad, rad^2].
  Eigen::Matrix3d cov_xy_yaw = Eigen::Matrix3d::Identity();
  double z_sigma_m = NAN;      ///< NaN: unknown height
  std::string heading_source;  ///< "heading topic" | "course over ground"
};

class GnssInitialPose {
 public:
  explicit GnssInitialPose(GnssInitialPoseOptions options);

  const GnssInitialPoseOptions& options() const { return options_; }
  void setLeverArm(const Eigen::Vector3d& antenna_in_base) {
    options_.antenna_in_base = antenna_in_base;
  }

  /// Records a heading (the newest is kept). Non-finite headings are ignored (returns false).
  bool addHeading(const GnssHeading& heading);

  /// A pose from this fix, or why not yet / not at all (no georeference, no solution, too
  /// coarse, outside the map's reach, waiting for a heading: moved d of course_min_distance_m).
  Result<GnssPoseEstimate> addFix(const Georeference& georeference, const GnssFix& fix);

  /// Forgets the fixes and heading seen (a map change, a new start).
  void reset();

 private:
  struct Track {
    double stamp_s;
    double x_m, y_m;
  };
  GnssInitialPoseOptions options_;
  bool have_heading_ = false;
  GnssHeading heading_;
  std::deque<Track> track_;  ///< antenna positions in the map frame, oldest first
};

}  // namespace gmm_localization
