// The simulated GNSS receiver (sim/gnss_model.h): statistics over long seeded runs (error RMS,
// the bias's correlation time, white noise between fixes), outages, determinism, options.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gmm_localization/sim/gnss_model.h"

using namespace gmm_localization;
using namespace gmm_localization::sim;

namespace {

GnssConfig realistic(uint64_t seed = 5) {
  GnssConfig c;
  c.mode = GnssMode::kRealistic;
  c.seed = seed;
  return c;
}

std::vector<GnssSample> run(const GnssConfig& c, double duration_s, double t_begin = 100.0) {
  GnssModel m(c, t_begin);
  std::vector<GnssSample> out;
  m.advanceTo(
      t_begin + duration_s, [](double t) { return Eigen::Vector3d(2.0 * t, -t, 5.0); }, &out);
  return out;
}

/// Autocorrelation of one axis of x at a lag in samples (means removed).
double autocorrelation(const std::vector<double>& x, size_t lag) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double num = 0.0, den = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    den += (x[i] - mean) * (x[i] - mean);
    if (i + lag < x.size()) num += (x[i] - mean) * (x[i + lag] - mean);
  }
  return num / den;
}

}  // namespace

TEST(SimGnss, RatesTimesAndTruth) {
  const auto s = run(realistic(), 10.0);
  ASSERT_EQ(s.size(), 50u);  // 5 Hz, [100, 110)
  for (size_t k = 0; k < s.size(); ++k) {
    EXPECT_NEAR(s[k].t, 100.0 + 0.2 * static_cast<double>(k), 1e-9);
    EXPECT_NEAR(s[k].truth.x(), 2.0 * s[k].t, 1e-9);
    EXPECT_TRUE(s[k].has_fix);
    EXPECT_TRUE((s[k].reported - s[k].truth - s[k].error).norm() < 1e-12);
    EXPECT_NEAR(s[k].horizontal_sigma_m, std::sqrt(0.5 * 0.5 + 1.0), 1e-12);
    EXPECT_NEAR(s[k].vertical_sigma_m, 1.5 * s[k].horizontal_sigma_m, 1e-12);
  }
}

TEST(SimGnss, ErrorRmsMatchesTheReportedSigmaAndTheDefaultsAreOneToThreeMetres) {
  // 20 seeds x 2000 s: 200 bias correlation times.
  double sum_h2 = 0.0, sum_up2 = 0.0;
  size_t n = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    for (const GnssSample& f : run(realistic(seed), 2000.0)) {
      sum_h2 += f.error.head<2>().squaredNorm();
      sum_up2 += f.error.z() * f.error.z();
      ++n;
    }
  }
  const double per_axis = std::sqrt(sum_h2 / (2.0 * n));
  const double horizontal = std::sqrt(sum_h2 / n);
  const double sigma = realistic().horizontalSigma();
  EXPECT_NEAR(per_axis, sigma, 0.07 * sigma);
  EXPECT_NEAR(std::sqrt(sum_up2 / n), 1.5 * sigma, 0.1 * 1.5 * sigma);
  EXPECT_GT(horizontal, 1.0);
  EXPECT_LT(horizontal, 3.0);
  std::printf("[sim_gnss] horizontal RMS %.3f m (per axis %.3f, reported sigma %.3f)\n", horizontal,
              per_axis, sigma);
}

TEST(SimGnss, BiasCorrelationTimeAndWhiteNoise) {
  GnssConfig c = realistic(9);
  c.bias_tau_s = 30.0;
  const auto s = run(c, 30000.0);  // 1000 correlation times, 150,000 fixes
  std::vector<double> bias, white;
  for (const GnssSample& f : s) {
    bias.push_back(f.bias.x());
    white.push_back(f.error.x() - f.bias.x());
  }
  const size_t lag_tau = static_cast<size_t>(c.bias_tau_s * c.rate_hz);
  // exp(-1) at one correlation time, exp(-2) at two; the white part is uncorrelated.
  EXPECT_NEAR(autocorrelation(bias, lag_tau), std::exp(-1.0), 0.05);
  EXPECT_NEAR(autocorrelation(bias, 2 * lag_tau), std::exp(-2.0), 0.05);
  EXPECT_NEAR(autocorrelation(bias, 1), std::exp(-1.0 / (c.bias_tau_s * c.rate_hz)), 0.01);
  EXPECT_NEAR(std::abs(autocorrelation(white, 1)), 0.0, 0.02);
  // Estimated time constant: the lag where the autocorrelation falls below exp(-1).
  size_t lag = 1;
  while (lag < bias.size() / 4 && autocorrelation(bias, lag) > std::exp(-1.0)) ++lag;
  const double tau_est = static_cast<double>(lag) / c.rate_hz;
  EXPECT_NEAR(tau_est, c.bias_tau_s, 0.2 * c.bias_tau_s);
  std::printf("[sim_gnss] bias correlation time %.1f s (configured %.1f s)\n", tau_est,
              c.bias_tau_s);
}

TEST(SimGnss, OutagesAreHonouredAndTheBiasRunsOnThroughThem) {
  GnssConfig c = realistic();
  c.outages = {{10.0, 5.0}, {30.0, 0.5}};
  GnssConfig without = realistic();
  const auto s = run(c, 60.0, 0.0);
  const auto w = run(without, 60.0, 0.0);
  ASSERT_EQ(s.size(), w.size());
  size_t missing = 0;
  for (size_t k = 0; k < s.size(); ++k) {
    const bool out = (s[k].t >= 10.0 && s[k].t < 15.0) || (s[k].t >= 30.0 && s[k].t < 30.5);
    EXPECT_EQ(s[k].has_fix, !out) << "t = " << s[k].t;
    missing += out;
    // The draws do not depend on the outages: the same errors as without them.
    EXPECT_EQ(s[k].error, w[k].error);
  }
  EXPECT_EQ(missing, 25u + 3u);
}

TEST(SimGnss, DeterministicAndSeeded) {
  const auto a = run(realistic(3), 100.0), b = run(realistic(3), 100.0),
             c = run(realistic(4), 100.0);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k].error, b[k].error);
  EXPECT_NE(a[0].error, c[0].error);
  // In pieces: the same fixes as in one call.
  GnssModel m(realistic(3), 100.0);
  std::vector<GnssSample> pieces;
  for (double t = 101.0; t <= 200.0; t += 7.3) {
    m.advanceTo(
        t, [](double t) { return Eigen::Vector3d(2.0 * t, -t, 5.0); }, &pieces);
  }
  m.advanceTo(
      200.0, [](double t) { return Eigen::Vector3d(2.0 * t, -t, 5.0); }, &pieces);
  ASSERT_EQ(pieces.size(), a.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(pieces[k].error, a[k].error);
}

TEST(SimGnss, BadOptionsAndOutageTexts) {
  EXPECT_TRUE(realistic().validate().ok());
  GnssConfig c = realistic();
  c.rate_hz = 0.0;
  EXPECT_FALSE(c.validate().ok());
  c = realistic();
  c.bias_tau_s = -1.0;
  EXPECT_FALSE(c.validate().ok());
  c = realistic();
  c.white_sigma_m = c.bias_sigma_m = 0.0;
  EXPECT_FALSE(c.validate().ok());
  c = realistic();
  c.outages = {{5.0, 0.0}};
  EXPECT_FALSE(c.validate().ok());
  auto o = parseGnssOutage("12.5:30");
  ASSERT_TRUE(o.ok());
  EXPECT_DOUBLE_EQ(o->start_s, 12.5);
  EXPECT_DOUBLE_EQ(o->duration_s, 30.0);
  for (const char* bad : {"", "12", "a:3", "3:", ":3", "-1:3", "3:0", "3:4:5"}) {
    EXPECT_FALSE(parseGnssOutage(bad).ok()) << bad;
  }
}
