#include "gmm_localization/core/map/gaussian_mixture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

double closedFormLog(const GaussianMixture1D& g, double z) {
  double p = 0.0;
  for (int j = 0; j < g.size(); ++j) {
    const auto& c = g.component(j);
    const double d = (z - c.mean_m) / c.sigma_m;
    p += c.weight / (std::sqrt(2.0 * M_PI) * c.sigma_m) * std::exp(-0.5 * d * d);
  }
  return std::log(p);
}

TEST(GaussianMixture, LogLikelihoodMatchesClosedForm) {
  GaussianMixture1D g;
  g.add({0.7f, 0.1f, 0.05f});
  g.add({0.3f, 2.5f, 0.8f});
  for (double z = -1.0; z <= 4.0; z += 0.0137) {
    EXPECT_NEAR(g.logLikelihood(z), closedFormLog(g, z), 1e-9) << "z=" << z;
  }
}

TEST(GaussianMixture, FarFromEveryModeStaysFinite) {
  GaussianMixture1D g;
  g.add({1.0f, 0.0f, 0.02f});
  const double ll = g.logLikelihood(1000.0);
  EXPECT_TRUE(std::isfinite(ll));
  EXPECT_LT(ll, -1e8);
  // The closed form underflows to log(0) here; log-sum-exp does not.
  EXPECT_FALSE(std::isfinite(closedFormLog(g, 1000.0)));
}

TEST(GaussianMixture, EmptyIsMinusInfinity) {
  GaussianMixture1D g;
  EXPECT_TRUE(std::isinf(g.logLikelihood(0.0)));
  EXPECT_TRUE(std::isinf(g.maxLogLikelihood(0.0, 1.0)));
}

TEST(GaussianMixture, AddRefusesBeyondCapacity) {
  GaussianMixture1D g;
  for (int j = 0; j < kMaxMixtureComponents; ++j) EXPECT_TRUE(g.add({0.1f, 0.f, 1.f}));
  EXPECT_FALSE(g.add({0.1f, 0.f, 1.f}));
  EXPECT_EQ(g.size(), kMaxMixtureComponents);
}

TEST(GaussianMixture, MaxOverIntervalBoundsEverySample) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    GaussianMixture1D g;
    const int k = 1 + trial % kMaxMixtureComponents;
    for (int j = 0; j < k; ++j) {
      g.add({static_cast<float>(1.0 / k), static_cast<float>(4.0 * u(rng) - 2.0),
             static_cast<float>(0.02 + 1.5 * u(rng) * u(rng))});
    }
    const double lo = 4.0 * u(rng) - 2.0;
    const double hi = lo + 0.05 + 0.5 * u(rng);
    const double bound = g.maxLogLikelihood(lo, hi);
    double sampled = -INFINITY;
    for (int i = 0; i <= 20000; ++i)
      sampled = std::max(sampled, g.logLikelihood(lo + (hi - lo) * i / 20000.0));
    EXPECT_GE(bound, sampled - 1e-9) << "trial " << trial;
    EXPECT_LE(bound, sampled + 1e-4) << "trial " << trial;  // and it is tight
  }
}

TEST(GaussianMixture, MahalanobisUsesNearestComponent) {
  GaussianMixture1D g;
  g.add({0.5f, 0.0f, 0.1f});
  g.add({0.5f, 5.0f, 1.0f});
  EXPECT_NEAR(g.mahalanobis(0.3), 3.0, 1e-6);
  EXPECT_NEAR(g.mahalanobis(4.0), 1.0, 1e-6);
}

// The mixture as modes() and the rasterizer evaluate it, with its constants computed once: the
// mixture's own logLikelihood bit for bit (the raster's bytes rest on it), on seeded random
// mixtures of 1-3 components and heights near and far from every component.
TEST(PreparedMixture, EqualsTheMixtureBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int c = 0; c < 2000; ++c) {
    GaussianMixture1D g;
    const int n = 1 + c % kMaxMixtureComponents;
    for (int j = 0; j < n; ++j) {
      g.add({static_cast<float>(0.05 + u(rng)), static_cast<float>(-5.0 + 10.0 * u(rng)),
             static_cast<float>(0.02 + 2.0 * u(rng))});
    }
    const PreparedMixture p(g);
    for (int k = 0; k < 50; ++k) {
      const double z = -30.0 + 60.0 * u(rng);
      EXPECT_EQ(p.logLikelihood(z), g.logLikelihood(z)) << "case " << c << " z " << z;
    }
  }
  EXPECT_EQ(PreparedMixture(GaussianMixture1D()).logLikelihood(1.0),
            -std::numeric_limits<double>::infinity());
}

/// MixtureLogTerms' value computed the plain way: every exp and the log, in component order.
double allTermsLog(const MixtureLogTerms& m, double z) {
  if (m.count == 0) return -std::numeric_limits<double>::infinity();
  double t[kMaxMixtureComponents];
  double peak = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < m.count; ++j) {
    const double d = (z - m.mean[j]) * m.inv_sigma[j];
    t[j] = m.log_norm[j] - 0.5 * d * d;
    peak = std::max(peak, t[j]);
  }
  if (m.count == 1 || !std::isfinite(peak)) return peak;
  double sum = 0.0;
  for (int j = 0; j < m.count; ++j) sum += std::exp(t[j] - peak);
  return peak + std::log(sum);
}

// The shortcuts (no exp and log when the other components are negligible, or when the nearest
// alone is below the floor) change no bit: checked against every exp and log on seeded random
// mixtures with components far apart, close together and identical, at heights near and far.
TEST(MixtureLogTerms, ShortcutsEqualEveryExpAndLogBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int shortcut_cases = 0;
  for (int c = 0; c < 3000; ++c) {
    GaussianMixture1D g;
    const int n = 1 + c % kMaxMixtureComponents;
    const double spread = c % 3 == 0 ? 0.05 : (c % 3 == 1 ? 1.0 : 10.0);
    for (int j = 0; j < n; ++j) {
      g.add({static_cast<float>(0.05 + u(rng)), static_cast<float>(spread * (u(rng) - 0.5)),
             static_cast<float>(0.03 + 0.3 * u(rng))});
    }
    if (c % 50 == 0 && n >= 2) {  // two identical components: a tie for the peak
      GaussianMixture1D tie;
      tie.add(g.component(0));
      tie.add(g.component(0));
      g = tie;
    }
    const MixtureLogTerms m(g);
    for (int k = 0; k < 40; ++k) {
      const double z = (k % 2 == 0 ? 2.0 : 20.0) * spread * (u(rng) - 0.5);
      const double reference = allTermsLog(m, z);
      ASSERT_EQ(m.logLikelihood(z), reference) << "case " << c << " z " << z;
      for (double floor : {-6.0, -2.0, 1.0}) {
        ASSERT_EQ(m.flooredLogLikelihood(z, floor), std::max(floor, reference))
            << "case " << c << " z " << z << " floor " << floor;
        shortcut_cases += reference < floor - 1.1 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(shortcut_cases, 1000);  // the floor shortcut was exercised
  const MixtureLogTerms empty;
  EXPECT_EQ(empty.logLikelihood(0.0), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(empty.flooredLogLikelihood(0.0, -6.0), -6.0);
}

}  // namespace
}  // namespace gmm_localization
