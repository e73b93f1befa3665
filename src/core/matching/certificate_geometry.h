#pragma once
// Where a node of a certificate's branch-and-bound (match_certificate.cpp, one heading per node;
// global_certificate.cpp, heading intervals) lies relative to the optimum, the exclusion zone
// and the window's border. Private to the matching stage.

#include <algorithm>
#include <cmath>

#include "gmm_localization/core/matching/match_certificate.h"

namespace gmm_localization {
namespace search_detail {

class CertificateGeometry {
 public:
  CertificateGeometry(const SearchProblem& problem, const SearchOutcome& optimum,
                      const CertificateOptions& o)
      : w_(problem.window()),
        res_(problem.map().geometry().resolution_m),
        ox_(optimum.tx),
        oy_(optimum.ty),
        oj_(optimum.heading_index),
        full_turn_(w_.sizeH() * w_.heading_step_rad >= 2.0 * M_PI),
        r_xy_(o.exclusion_radius_m),
        r_h_(o.exclusion_heading_rad) {}

  struct Extent {
    double max_xy_m;     ///< farthest x-y distance of a pose of the node from the optimum
    double heading_rad;  ///< farthest heading distance (around the circle on a full turn)
    bool inside;         ///< every pose of the node is inside the exclusion zone
    bool border;         ///< the node holds a pose on the window's border
  };

  /// The node of translations [tx, tx + 2^layer) x [ty, ty + 2^layer) (cut at the window) and
  /// headings [j0, j1].
  Extent of(int tx, int ty, int layer, int j0, int j1) const {
    const int size = 1 << layer;
    const int tx1 = std::min(tx + size - 1, w_.sizeX() - 1);
    const int ty1 = std::min(ty + size - 1, w_.sizeY() - 1);
    const double dx = std::max(std::abs(tx - ox_), std::abs(tx1 - ox_)) * res_;
    const double dy = std::max(std::abs(ty - oy_), std::abs(ty1 - oy_)) * res_;
    Extent e;
    e.max_xy_m = std::hypot(dx, dy);
    e.heading_rad = headingReach(j0, j1);
    e.inside = e.max_xy_m <= r_xy_ && e.heading_rad <= r_h_;
    // An axis with one value is not searched: its border is not a border of the set; nor are
    // the headings of a full turn.
    e.border = (w_.sizeX() > 1 && (tx == 0 || tx1 == w_.sizeX() - 1)) ||
               (w_.sizeY() > 1 && (ty == 0 || ty1 == w_.sizeY() - 1)) ||
               (!full_turn_ && w_.sizeH() > 1 && (j0 == 0 || j1 == w_.sizeH() - 1));
    return e;
  }

 private:
  /// Largest heading distance from the optimum's over headings [j0, j1].
  double headingReach(int j0, int j1) const {
    const double a0 = (j0 - oj_) * w_.heading_step_rad;
    const double a1 = (j1 - oj_) * w_.heading_step_rad;
    if (!full_turn_) return std::max(std::abs(a0), std::abs(a1));
    // Around the circle: pi when the interval holds an odd multiple of pi, else an end's.
    double k = std::ceil(a0 / M_PI);
    if (std::fmod(std::abs(k), 2.0) == 0.0) k += 1.0;
    if (k * M_PI <= a1) return M_PI;
    return std::max(std::abs(std::remainder(a0, 2.0 * M_PI)),
                    std::abs(std::remainder(a1, 2.0 * M_PI)));
  }

  const SearchWindow& w_;
  double res_;
  int ox_, oy_, oj_;
  bool full_turn_;
  double r_xy_, r_h_;
};

}  // namespace search_detail
}  // namespace gmm_localization
