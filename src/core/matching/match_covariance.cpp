#include "gmm_localization/core/matching/match_covariance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace gmm_localization {

std::string CovarianceOptions::validate() const {
  if (!(radius_m > 0.0) || heading_radius < 0) {
    return "radius_m must be > 0 and heading_radius >= 0";
  }
  if (!(temperature_per_point > 0.0)) return "temperature_per_point must be > 0";
  if (!(min_sigma_xy_m > 0.0 && min_sigma_yaw_rad > 0.0)) return "minimum sigmas must be > 0";
  if (!(edge_mass_limit > 0.0 && edge_mass_limit <= 1.0)) return "edge_mass_limit in (0, 1]";
  if (max_points > 0 && max_points < 100) return "max_points must be 0 (all) or >= 100";
  return {};
}

MatchCovariance searchCovariance(const SearchProblem& problem, const SearchOutcome& optimum,
                                 const CovarianceOptions& o, TaskPool* pool) {
  const SearchWindow& w = problem.window();
  const double res = problem.map().geometry().resolution_m;
  const int r = std::max(1, static_cast<int>(std::round(o.radius_m / res)));
  const int tx0 = std::max(0, optimum.tx - r), tx1 = std::min(w.sizeX() - 1, optimum.tx + r);
  const int ty0 = std::max(0, optimum.ty - r), ty1 = std::min(w.sizeY() - 1, optimum.ty + r);
  const int j0 = std::max(0, optimum.heading_index - o.heading_radius);
  const int j1 = std::min(w.sizeH() - 1, optimum.heading_index + o.heading_radius);
  const int nx = tx1 - tx0 + 1, ny = ty1 - ty0 + 1;

  // Score the neighbourhood (on a thinned point set when asked), heading by heading.
  const size_t prepared = static_cast<size_t>(problem.preparedPoints(optimum.heading_index));
  const int stride = o.max_points > 0 && prepared > o.max_points
                         ? static_cast<int>((prepared + o.max_points - 1) / o.max_points)
                         : 1;
  // Scores in whole-scan units: each heading's thinned sum scaled by the scan points over the
  // points it scored (exact when nothing is thinned).
  // Headings in parallel (each fills its own row).
  std::vector<std::vector<double>> scores(j1 - j0 + 1);
  parallelFor(pool, j1 - j0 + 1, [&](int k) {
    std::vector<int64_t> block;
    const int64_t scored = problem.scoreBlock(j0 + k, tx0, ty0, nx, ny, block, stride);
    const double to_scan = static_cast<double>(problem.scanPoints()) /
                           static_cast<double>(std::max<int64_t>(1, scored));
    std::vector<double>& s = scores[static_cast<size_t>(k)];
    s.resize(block.size());
    for (size_t i = 0; i < block.size(); ++i) s[i] = static_cast<double>(block[i]) * to_scan;
  });
  double peak = -std::numeric_limits<double>::infinity();
  for (const std::vector<double>& row : scores) {
    for (double v : row) peak = std::max(peak, v);
  }
  const ScoreQuantizer q(problem.map().options());
  const double temperature = o.temperature_per_point * std::max<int64_t>(1, problem.scanPoints());
  const double scale = q.step() / temperature;  // score units -> exponent

  MatchCovariance out;
  double mass = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  Eigen::Vector3d edge = Eigen::Vector3d::Zero();
  for (int j = j0; j <= j1; ++j) {
    for (int iy = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix) {
        const double p =
            std::exp((scores[j - j0][static_cast<size_t>(iy) * nx + ix] - peak) * scale);
        const Eigen::Vector3d d((tx0 + ix - optimum.tx) * res, (ty0 + iy - optimum.ty) * res,
                                (j - optimum.heading_index) * w.heading_step_rad);
        mass += p;
        mean += p * d;
        second += p * d * d.transpose();
        // Edges that are the window's own bounds are not truncation: the window ends there.
        if ((ix == 0 && tx0 > 0) || (ix == nx - 1 && tx1 < w.sizeX() - 1)) edge.x() += p;
        if ((iy == 0 && ty0 > 0) || (iy == ny - 1 && ty1 < w.sizeY() - 1)) edge.y() += p;
        if ((j == j0 && j0 > 0) || (j == j1 && j1 < w.sizeH() - 1)) edge.z() += p;
        ++out.poses;
      }
    }
  }
  mean /= mass;
  Eigen::Matrix3d cov = second / mass - mean * mean.transpose();
  // Discretisation: the true pose is anywhere within the optimum's cell and heading step.
  cov(0, 0) += res * res / 12.0;
  cov(1, 1) += res * res / 12.0;
  cov(2, 2) += w.heading_step_rad * w.heading_step_rad / 12.0;
  out.edge_mass = edge / mass;
  const Eigen::Vector3d window_var((w.sizeX() * res) * (w.sizeX() * res) / 12.0,
                                   (w.sizeY() * res) * (w.sizeY() * res) / 12.0,
                                   std::pow(w.sizeH() * w.heading_step_rad, 2) / 12.0);
  const Eigen::Vector3d floor_var(o.min_sigma_xy_m * o.min_sigma_xy_m,
                                  o.min_sigma_xy_m * o.min_sigma_xy_m,
                                  o.min_sigma_yaw_rad * o.min_sigma_yaw_rad);
  for (int a = 0; a < 3; ++a) {
    double target = std::max(cov(a, a), floor_var(a));
    if (out.edge_mass(a) > o.edge_mass_limit) target = std::max(target, window_var(a));
    if (target > cov(a, a)) {
      // Grow the variance of this axis, keeping the correlations.
      const double s = std::sqrt(target / std::max(cov(a, a), 1e-300));
      cov.row(a) *= s;
      cov.col(a) *= s;
    }
  }
  out.covariance = 0.5 * (cov + cov.transpose());
  return out;
}

}  // namespace gmm_localization
