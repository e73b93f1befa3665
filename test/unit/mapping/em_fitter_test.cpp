#include "gmm_localization/core/mapping/em_fitter.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

struct Truth {
  double weight, mean, sigma;
};

std::vector<WeightedSample> draw(const std::vector<Truth>& truth, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<double> cum;
  double c = 0.0;
  for (const auto& t : truth) cum.push_back(c += t.weight);
  std::uniform_real_distribution<double> u(0.0, c);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<WeightedSample> out;
  for (int i = 0; i < n; ++i) {
    const double r = u(rng);
    size_t j = 0;
    while (j + 1 < truth.size() && r > cum[j]) ++j;
    out.push_back({truth[j].mean + truth[j].sigma * g(rng), 1.0, 1.0});
  }
  return out;
}

void expectFinite(const EmFitResult& r) {
  EXPECT_TRUE(std::isfinite(r.log_likelihood));
  EXPECT_TRUE(std::isfinite(r.criterion_value));
  for (int j = 0; j < r.mixture.size(); ++j) {
    const auto& c = r.mixture.component(j);
    EXPECT_TRUE(std::isfinite(c.mean_m));
    EXPECT_TRUE(std::isfinite(c.sigma_m));
    EXPECT_GT(c.sigma_m, 0.f);
    EXPECT_GT(c.weight, 0.f);
  }
}

TEST(EmFitter, RecoversOneComponent) {
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const auto s = draw({{1.0, 1.5, 0.1}}, 2000, seed);
    EmFitter fitter;
    const auto r = fitter.fit(s);
    ASSERT_EQ(r.mixture.size(), 1) << "seed " << seed;
    EXPECT_NEAR(r.mixture.component(0).mean_m, 1.5, 0.01);
    EXPECT_NEAR(r.mixture.component(0).sigma_m, 0.1, 0.01);
    EXPECT_FLOAT_EQ(r.mixture.component(0).weight, 1.f);
    EXPECT_NEAR(r.effective_samples, 2000.0, 1e-6);
    expectFinite(r);
  }
}

TEST(EmFitter, RecoversTwoComponents) {
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const auto s = draw({{0.7, 0.0, 0.05}, {0.3, 3.0, 0.3}}, 3000, seed);
    EmFitter fitter;
    const auto r = fitter.fit(s);
    ASSERT_EQ(r.mixture.size(), 2) << "seed " << seed;
    const auto& a = r.mixture.component(0);
    const auto& b = r.mixture.component(1);
    EXPECT_NEAR(a.mean_m, 0.0, 0.01);
    EXPECT_NEAR(a.sigma_m, 0.05, 0.005);
    EXPECT_NEAR(a.weight, 0.7, 0.03);
    EXPECT_NEAR(b.mean_m, 3.0, 0.05);
    EXPECT_NEAR(b.sigma_m, 0.3, 0.03);
    EXPECT_NEAR(b.weight, 0.3, 0.03);
    EXPECT_NEAR(a.weight + b.weight, 1.f, 1e-6);
  }
}

TEST(EmFitter, SmallMinorityModeFromFarthestPointSeeding) {
  // 93% ground, 7% overhang: quantile seeding alone would put both seeds in the ground.
  const auto s = draw({{0.93, -1.7, 0.03}, {0.07, 2.4, 0.05}}, 1500, 7);
  EmFitter fitter;
  const auto r = fitter.fit(s);
  ASSERT_EQ(r.mixture.size(), 2);
  EXPECT_NEAR(r.mixture.component(0).mean_m, -1.7, 0.01);
  EXPECT_NEAR(r.mixture.component(1).mean_m, 2.4, 0.02);
  EXPECT_NEAR(r.mixture.component(1).weight, 0.07, 0.02);
}

TEST(EmFitter, ThreeComponentsWhenAllowed) {
  const auto s = draw({{0.5, 0.0, 0.05}, {0.3, 2.0, 0.1}, {0.2, 5.0, 0.2}}, 3000, 3);
  EmFitterOptions o;
  o.max_components = 3;
  EmFitter fitter(o);
  const auto r = fitter.fit(s);
  ASSERT_EQ(r.mixture.size(), 3);
  EXPECT_NEAR(r.mixture.component(0).mean_m, 0.0, 0.01);
  EXPECT_NEAR(r.mixture.component(1).mean_m, 2.0, 0.02);
  EXPECT_NEAR(r.mixture.component(2).mean_m, 5.0, 0.05);
  EmFitter two;  // default K_max = 2 never returns three
  EXPECT_LE(two.fit(s).mixture.size(), 2);
}

TEST(EmFitter, PicksOneForOneGaussianAcrossSeeds) {
  int ones = 0;
  for (uint32_t seed = 100; seed < 120; ++seed) {
    EmFitter fitter;
    ones += fitter.fit(draw({{1.0, 0.2, 0.04}}, 400, seed)).mixture.size() == 1;
  }
  EXPECT_EQ(ones, 20);
}

TEST(EmFitter, UniformWallIsOneComponentUnderIclButSplitByBic) {
  // A wall from 0 to 8 m sampled uniformly: not Gaussian. ICL keeps one wide component; BIC
  // with thousands of returns splits it into overlapping Gaussians (why ICL is the default).
  std::vector<WeightedSample> s;
  for (int i = 0; i < 4000; ++i) s.push_back({8.0 * (i + 0.5) / 4000.0, 1.0, 1.0});
  EmFitter icl;
  const auto r = icl.fit(s);
  ASSERT_EQ(r.mixture.size(), 1);
  EXPECT_NEAR(r.mixture.component(0).mean_m, 4.0, 1e-3);
  EXPECT_NEAR(r.mixture.component(0).sigma_m, 8.0 / std::sqrt(12.0), 1e-3);
  EmFitterOptions o;
  o.criterion = ModelSelection::kBic;
  EmFitter bic(o);
  EXPECT_EQ(bic.fit(s).mixture.size(), 2);
}

TEST(EmFitter, HistogramBinsEqualRawSamples) {
  // The same returns given raw or as 1 mm bins (weight = weight_sq = count) fit the same.
  const auto raw = draw({{0.6, 0.0, 0.04}, {0.4, 1.2, 0.2}}, 2000, 11);
  std::map<long, int> bins;
  for (const auto& s : raw) ++bins[std::lround(s.z_m * 1000.0)];
  std::vector<WeightedSample> hist;
  std::vector<WeightedSample> quantised;
  for (const auto& [b, c] : bins) {
    hist.push_back({b / 1000.0, double(c), double(c)});
    for (int i = 0; i < c; ++i) quantised.push_back({b / 1000.0, 1.0, 1.0});
  }
  EmFitter f1, f2;
  const auto a = f1.fit(hist);
  const auto b = f2.fit(quantised);
  EXPECT_NEAR(a.effective_samples, 2000.0, 1e-6);
  ASSERT_EQ(a.mixture.size(), b.mixture.size());
  for (int j = 0; j < a.mixture.size(); ++j) {
    EXPECT_NEAR(a.mixture.component(j).mean_m, b.mixture.component(j).mean_m, 1e-4);
    EXPECT_NEAR(a.mixture.component(j).sigma_m, b.mixture.component(j).sigma_m, 1e-4);
    EXPECT_NEAR(a.mixture.component(j).weight, b.mixture.component(j).weight, 1e-4);
  }
}

TEST(EmFitter, KishEffectiveSampleSize) {
  // 10 returns with weight 1 and 40 blurred-in returns with kernel weight 0.25, one per sample.
  std::vector<WeightedSample> s;
  for (int i = 0; i < 10; ++i) s.push_back({0.01 * i, 1.0, 1.0});
  for (int i = 0; i < 40; ++i) s.push_back({0.005 * i, 0.25, 0.0625});
  EmFitter fitter;
  const auto r = fitter.fit(s);
  const double w = 10.0 + 40.0 * 0.25, wsq = 10.0 + 40.0 * 0.0625;
  EXPECT_NEAR(r.total_weight, w, 1e-9);
  EXPECT_NEAR(r.effective_samples, w * w / wsq, 1e-9);
}

TEST(EmFitter, OrderDoesNotMatter) {
  auto s = draw({{0.5, 0.0, 0.05}, {0.5, 2.0, 0.5}}, 800, 5);
  EmFitter fitter;
  const auto a = fitter.fit(s);
  std::mt19937 rng(3);
  std::shuffle(s.begin(), s.end(), rng);
  const auto b = fitter.fit(s);
  EXPECT_TRUE(a.mixture == b.mixture);
}

TEST(EmFitter, DegenerateInputsNeverNaN) {
  EmFitter fitter;
  // No samples, zero weights, non-finite values: an empty mixture with a reason.
  auto r = fitter.fit(std::vector<WeightedSample>{});
  EXPECT_TRUE(r.mixture.empty());
  EXPECT_FALSE(r.reason.empty());
  r = fitter.fit({{1.0, 0.0, 0.0}, {2.0, 0.0, 0.0}});
  EXPECT_TRUE(r.mixture.empty());
  EXPECT_NE(r.reason.find("zero total weight"), std::string::npos) << r.reason;
  r = fitter.fit({{NAN, 1.0, 1.0}, {INFINITY, 1.0, 1.0}, {0.0, NAN, 1.0}, {0.0, -1.0, 1.0}});
  EXPECT_TRUE(r.mixture.empty());
  // One point: one component at the floor.
  r = fitter.fit({{2.5, 1.0, 1.0}});
  ASSERT_EQ(r.mixture.size(), 1);
  EXPECT_FLOAT_EQ(r.mixture.component(0).mean_m, 2.5f);
  EXPECT_FLOAT_EQ(r.mixture.component(0).sigma_m, 0.03f);
  expectFinite(r);
  // All equal z: one component at the floor, whatever K_max.
  EmFitterOptions o3;
  o3.max_components = 3;
  EmFitter f3(o3);
  r = f3.fit(std::vector<WeightedSample>(1000, {-1.25, 1.0, 1.0}));
  ASSERT_EQ(r.mixture.size(), 1);
  EXPECT_FLOAT_EQ(r.mixture.component(0).sigma_m, 0.03f);
  r = f3.fitFixed(std::vector<WeightedSample>(50, {-1.25, 1.0, 1.0}).data(), 50, 3);
  EXPECT_EQ(r.mixture.size(), 1);
  expectFinite(r);
  // Two points far apart: too little evidence for two components.
  r = fitter.fit({{0.0, 1.0, 1.0}, {5.0, 1.0, 1.0}});
  ASSERT_EQ(r.mixture.size(), 1);
  EXPECT_NEAR(r.mixture.component(0).sigma_m, 2.5, 1e-5);
  // Huge spread and huge weights stay finite.
  std::vector<WeightedSample> huge;
  for (int i = 0; i < 100; ++i) huge.push_back({(i % 2 ? 1e6 : -1e6) + i, 1e300, 1e300});
  r = fitter.fit(huge);
  ASSERT_GE(r.mixture.size(), 1);
  expectFinite(r);
  // Tiny weights stay finite, and the fit does not depend on the weight scale.
  auto s = draw({{1.0, 0.0, 0.1}}, 200, 9);
  const auto ref = fitter.fit(s);
  for (auto& x : s) x = {x.z_m, 1e-300, 1e-300 * 1e-300};  // wsq underflows to 0
  r = fitter.fit(s);
  ASSERT_EQ(r.mixture.size(), 1);
  EXPECT_NEAR(r.mixture.component(0).mean_m, ref.mixture.component(0).mean_m, 1e-6);
  expectFinite(r);
}

TEST(EmFitter, VarianceFloorHolds) {
  EmFitterOptions o;
  o.sigma_floor_m = 0.05;
  EmFitter fitter(o);
  const auto r = fitter.fit(draw({{0.5, 0.0, 0.001}, {0.5, 1.0, 0.001}}, 500, 2));
  ASSERT_EQ(r.mixture.size(), 2);
  for (int j = 0; j < 2; ++j) EXPECT_GE(r.mixture.component(j).sigma_m, 0.05f - 1e-7f);
}

TEST(EmFitter, OptionsValidateNamesTheField) {
  EmFitterOptions o;
  EXPECT_TRUE(o.validate().empty());
  o.max_components = 4;
  EXPECT_NE(o.validate().find("max_components"), std::string::npos);
  o = EmFitterOptions();
  o.sigma_floor_m = 0.0;
  EXPECT_NE(o.validate().find("sigma_floor_m"), std::string::npos);
  o = EmFitterOptions();
  o.tolerance = NAN;
  EXPECT_NE(o.validate().find("tolerance"), std::string::npos);
  o = EmFitterOptions();
  o.min_component_weight = 0.7;
  EXPECT_NE(o.validate().find("min_component_weight"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
