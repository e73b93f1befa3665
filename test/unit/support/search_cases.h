#pragma once
// Seeded search windows and the outcome comparison shared by the search tests.

#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/matching/grid_search.h"

namespace gmm_localization {
namespace testing {

/// A window around a uniform random prior in [-xy, xy]^2 (z in [0, z_max), any heading), with
/// half extents in [half_min, half_min + half_span) [m] and half heading below heading_max.
inline SearchWindow randomWindow(std::mt19937& rng, double xy, double z_max, double half_min,
                                 double half_span, double heading_max) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Pose6 prior;
  prior.x = -xy + 2.0 * xy * u(rng);
  prior.y = -xy + 2.0 * xy * u(rng);
  prior.z = z_max * u(rng);
  prior.yaw = 6.28 * u(rng);
  const double half_x = half_min + half_span * u(rng);
  const double half_y = half_min + half_span * u(rng);
  const double half_heading = heading_max * u(rng);
  return SearchWindow::fromExtent(prior, half_x, half_y, half_heading, 0.02, 0.2);
}

inline void expectSame(const SearchOutcome& a, const SearchOutcome& b, int c) {
  EXPECT_EQ(a.score, b.score) << "case " << c;
  EXPECT_EQ(a.heading_index, b.heading_index) << "case " << c;
  EXPECT_EQ(a.tx, b.tx) << "case " << c;
  EXPECT_EQ(a.ty, b.ty) << "case " << c;
}

}  // namespace testing
}  // namespace gmm_localization
