#pragma once
// A measurement covariance for x, y and heading from the explored search space, after Olson,
// "Real-Time Correlative Scan Matching" (ICRA 2009): the base-layer scores of a neighbourhood
// of the optimum are turned into a distribution p_i ~ exp((LL_i - LL_max) / T) whose second
// moment is the covariance. Where the score is flat (a corridor) the distribution is wide, so
// the covariance is larger along the corridor than across it.

#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/matching/grid_search.h"

namespace gmm_localization {

struct CovarianceOptions {
  double radius_m = 1.6;   ///< neighbourhood half-size in x and y [m]
  int heading_radius = 3;  ///< neighbourhood half-size in heading steps
  /// The scan's points are far from independent observations (neighbours share map cells and
  /// errors): the temperature T = temperature_per_point * n [nats] tempers Eq. 1's sum.
  double temperature_per_point = 0.05;
  double min_sigma_xy_m = 0.03;  ///< floors of the reported standard deviations
  double min_sigma_yaw_rad = 0.002;
  /// When more than this share of the mass lies on the neighbourhood's edge along an axis, the
  /// distribution is truncated there: that axis gets at least the variance of a uniform
  /// distribution over the whole search window (conservative).
  double edge_mass_limit = 0.05;
  /// Prepared search points scored per pose (evenly thinned; 0: all). The tempered
  /// distribution scales with the points scored, so a subset estimates the same covariance at
  /// a fraction of the table reads.
  size_t max_points = 2000;

  std::string validate() const;
};

struct MatchCovariance {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< x [m], y [m], yaw [rad]
  int poses = 0;                                             ///< neighbourhood poses scored
  Eigen::Vector3d edge_mass = Eigen::Vector3d::Zero();       ///< per axis, share on the edge
};

/// `pool`: the neighbourhood's headings scored in parallel (the same result).
MatchCovariance searchCovariance(const SearchProblem& problem, const SearchOutcome& optimum,
                                 const CovarianceOptions& options, TaskPool* pool = nullptr);

}  // namespace gmm_localization
