// The EKF's optional GNSS input (LocalizationFilter::addGnss, gnss_position.h): fixes made with
// mapToGeodetic from a known map position in a georeferenced map; the filter converges to the
// position from fixes alone, its covariance covers a receiver's bias (and would not with fixes
// taken as independent), scan matches pin the pose while the fixes calibrate the bias, a 50 m
// jump is gated out and counted, a fix without a solution is refused with its reason, and with
// the input off nothing changes. Fixed seeds.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/localization/gnss_position.h"
#include "gmm_localization/core/localization/localization_filter.h"
#include "support/test_georeference.h"

namespace gmm_localization {
namespace {

Georeference georeference() { return testing::simulatorGeoreference(); }

/// A fix of the map point (x, y, z) reporting sigma per horizontal axis.
GnssFix fixAt(double stamp, double x, double y, double z, double sigma) {
  auto geo = mapToGeodetic(georeference(), x, y, z);
  EXPECT_TRUE(geo.ok());
  GnssFix f;
  f.stamp_s = stamp;
  f.position = *geo;
  f.east_var_m2 = f.north_var_m2 = sigma * sigma;
  f.up_var_m2 = 2.25 * sigma * sigma;
  return f;
}

LocalizationFilter makeFilter(bool gnss, bool estimate_bias = true) {
  FilterPolicyOptions p;
  p.gnss_enabled = gnss;
  EkfOptions e;
  e.estimate_gnss_bias = estimate_bias;
  auto f = LocalizationFilter::create(e, p);
  EXPECT_TRUE(f.ok()) << f.error();
  f->setGeoreference(georeference());
  return std::move(f).value();
}

/// Starts the filter 12 m off the truth (300, 200) with a 20 m sigma.
void start(LocalizationFilter* f) {
  Pose6 p;
  p.x = 312.0;
  p.y = 191.0;
  p.yaw = 0.4;
  Matrix6d c = Matrix6d::Identity() * 0.01;
  c(0, 0) = c(1, 1) = 400.0;
  ASSERT_TRUE(f->setInitialPose(p, c, 0.0, true).ok());
}

/// Zero twist at 50 Hz (a vehicle standing still), fixes at 5 Hz with white noise of `sigma`
/// plus a constant receiver bias, scan matches of the truth (3 cm) at 10 Hz when `matches`.
void run(LocalizationFilter* f, double t0, double t1, std::mt19937* rng, double sigma = 1.1,
         bool fixes = true, const Eigen::Vector2d& bias = Eigen::Vector2d::Zero(),
         bool matches = false) {
  std::normal_distribution<double> n(0.0, sigma);
  const int steps = static_cast<int>(std::lround((t1 - t0) / 0.02));
  for (int k = 0; k < steps; ++k) {
    const double t = t0 + 0.02 * k;
    TwistMeasurement tw;
    tw.stamp_s = t;
    tw.covariance = Matrix6d::Identity() * 1e-4;
    f->addTwist(tw);
    if (fixes && k % 10 == 0) {
      const FuseReport r =
          f->addGnss(fixAt(t, 300.0 + bias.x() + n(*rng), 200.0 + bias.y() + n(*rng), 0.0, sigma));
      EXPECT_TRUE(r.fused()) << r.reason << " d2 " << r.mahalanobis_sq;
    }
    if (matches && k % 5 == 0) {
      Pose6 p;
      p.x = 300.0;
      p.y = 200.0;
      p.yaw = 0.4;
      const FuseReport r = f->addMatch(t, p, Matrix6d::Identity() * 0.03 * 0.03);
      EXPECT_TRUE(r.fused()) << r.reason << " d2 " << r.mahalanobis_sq;
    }
  }
}

double horizontalError(const LocalizationFilter& f) {
  const EkfState& s = f.ekf().state();
  return std::hypot(s.x(kStateX) - 300.0, s.x(kStateY) - 200.0);
}

TEST(GnssEkfInput, ConvergesToAFixedPositionFromFixesAlone) {
  LocalizationFilter f = makeFilter(true);
  start(&f);
  std::mt19937 rng(7);
  run(&f, 0.0, 120.0, &rng);
  const double err = horizontalError(f);
  const EkfDiagnostics d = f.ekf().diagnostics();
  const double sigma = d.max_horizontal_sigma_m;
  std::printf("[gnss_ekf_input] after 600 unbiased fixes: error %.3f m, horizontal sigma %.3f m\n",
              err, sigma);
  EXPECT_LT(err, 0.3);
  // The fixes cannot tell the position from the receiver's bias (1 m): the filter stays that
  // unsure, however many fixes came.
  EXPECT_GT(sigma, 0.7);
  EXPECT_LT(sigma, 1.5);
  EXPECT_EQ(d.source(MeasurementSource::kGnssPosition).fused, 600u);
  EXPECT_EQ(d.source(MeasurementSource::kGnssPosition).rejected_gate, 0u);
}

TEST(GnssEkfInput, ABiasedReceiverStaysInsideTheCovarianceOnlyWithTheBiasState) {
  // A receiver 1.5 m off (1.5 sigma of the bias model) for two minutes, no scan matches.
  const Eigen::Vector2d bias(1.2, -0.9);
  LocalizationFilter with_bias = makeFilter(true), independent = makeFilter(true, false);
  start(&with_bias);
  start(&independent);
  std::mt19937 a(11), b(11);
  run(&with_bias, 0.0, 120.0, &a, 0.5, true, bias);
  run(&independent, 0.0, 120.0, &b, 0.5, true, bias);
  const double err_bias = horizontalError(with_bias);
  const double err_indep = horizontalError(independent);
  const double sigma_bias = with_bias.ekf().diagnostics().max_horizontal_sigma_m;
  const double sigma_indep = independent.ekf().diagnostics().max_horizontal_sigma_m;
  std::printf(
      "[gnss_ekf_input] biased receiver, 120 s: with the bias state error %.2f m, sigma %.2f m; "
      "fixes as independent error %.2f m, sigma %.2f m\n",
      err_bias, sigma_bias, err_indep, sigma_indep);
  EXPECT_NEAR(err_bias, bias.norm(), 0.3);  // the fixes' mean: nothing else to go by
  EXPECT_LT(err_bias, 3.0 * sigma_bias);    // ... but the covariance says so
  EXPECT_NEAR(err_indep, bias.norm(), 0.3);
  EXPECT_GT(err_indep, 3.0 * sigma_indep);  // what the bias state mends: sure of a wrong mean
}

TEST(GnssEkfInput, MatchesPinThePoseAndTheFixesCalibrateTheBias) {
  const Eigen::Vector2d bias(1.2, -0.9);
  LocalizationFilter f = makeFilter(true);
  start(&f);
  std::mt19937 rng(12);
  run(&f, 0.0, 60.0, &rng, 0.5, true, bias, true);
  const EkfDiagnostics d = f.ekf().diagnostics();
  std::printf(
      "[gnss_ekf_input] with matches, 60 s: error %.3f m, bias estimate (%.2f, %.2f) m, sigma "
      "%.2f m\n",
      horizontalError(f), d.gnss_bias_m.x(), d.gnss_bias_m.y(), d.gnss_bias_sigma_m);
  EXPECT_LT(horizontalError(f), 0.02);  // the fixes do not pull the matched pose
  // A bias that wanders with tau = 60 s is known from the last minute of fixes only: about
  // 0.2 m from 0.5 m fixes at 5 Hz (the Riccati equation's steady state).
  EXPECT_LT(d.gnss_bias_sigma_m, 0.3);
  EXPECT_LT((d.gnss_bias_m - bias).norm(), 3.0 * d.gnss_bias_sigma_m);
  // Matching stops (snow): ten seconds on the fixes alone start from the calibrated bias.
  run(&f, 60.0, 70.0, &rng, 0.5, true, bias, false);
  const double err = horizontalError(f);
  std::printf("[gnss_ekf_input] then 10 s on fixes alone: error %.3f m\n", err);
  EXPECT_LT(err, 0.3);
}

TEST(GnssEkfInput, GatingRejectsA50mJump) {
  LocalizationFilter f = makeFilter(true);
  start(&f);
  std::mt19937 rng(8);
  run(&f, 0.0, 60.0, &rng);
  const Eigen::Vector2d before = f.ekf().state().x.head<2>();
  const FuseReport r = f.addGnss(fixAt(60.0, 350.0, 200.0, 0.0, 1.1));
  EXPECT_EQ(r.outcome, FuseOutcome::kRejectedGate) << r.reason;
  EXPECT_GT(r.mahalanobis_sq, r.gate_threshold_sq);
  EXPECT_LT((f.ekf().state().x.head<2>() - before).norm(), 0.05);
  EXPECT_EQ(f.ekf().diagnostics().source(MeasurementSource::kGnssPosition).rejected_gate, 1u);
  // The next good fixes are fused again.
  run(&f, 60.02, 62.0, &rng);
}

TEST(GnssEkfInput, RefusesFixesWithoutSolutionOrGeoreference) {
  LocalizationFilter f = makeFilter(true);
  GnssFix fix = fixAt(0.0, 300.0, 200.0, 0.0, 1.0);
  EXPECT_EQ(f.addGnss(fix).outcome, FuseOutcome::kRejectedNotInitialized);
  start(&f);
  fix.stamp_s = 0.1;
  fix.has_solution = false;
  FuseReport r = f.addGnss(fix);
  EXPECT_EQ(r.outcome, FuseOutcome::kRejectedInvalid);
  EXPECT_NE(r.reason.find("no fix"), std::string::npos) << r.reason;
  EXPECT_EQ(f.gnssRefused(), 1u);
  f.setGeoreference(Georeference{});
  fix.has_solution = true;
  r = f.addGnss(fix);
  EXPECT_NE(r.reason.find("no georeference"), std::string::npos) << r.reason;
  EXPECT_EQ(f.gnssRefused(), 2u);
}

TEST(GnssEkfInput, WithoutTheOptionNothingChanges) {
  LocalizationFilter with_fixes = makeFilter(false), without = makeFilter(false);
  start(&with_fixes);
  start(&without);
  std::mt19937 a(9), b(9);
  for (double t = 0.0; t < 10.0; t += 0.02) {
    TwistMeasurement tw;
    tw.stamp_s = t;
    tw.linear_mps = Eigen::Vector3d(5.0, 0.0, 0.0);
    tw.covariance = Matrix6d::Identity() * 1e-4;
    with_fixes.addTwist(tw);
    without.addTwist(tw);
    const FuseReport r = with_fixes.addGnss(fixAt(t, 300.0, 200.0, 0.0, 1.0));
    EXPECT_EQ(r.outcome, FuseOutcome::kRejectedInvalid);
  }
  EXPECT_EQ(with_fixes.ekf().state().x, without.ekf().state().x);
  EXPECT_EQ(with_fixes.ekf().state().P, without.ekf().state().P);
  EXPECT_EQ(with_fixes.ekf().diagnostics().source(MeasurementSource::kGnssPosition).fused, 0u);
}

TEST(GnssEkfInput, MeasurementRemovesTheLeverArmAndRotatesTheCovariance) {
  GnssPositionOptions o;
  o.antenna_in_base = Eigen::Vector3d(1.0, 0.5, 1.8);
  const double yaw = 0.7;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const Eigen::Vector3d base(120.0, -40.0, 3.0);
  const Eigen::Vector3d antenna = base + Eigen::Vector3d(c * 1.0 - s * 0.5, s * 1.0 + c * 0.5, 1.8);
  GnssFix fix = fixAt(1.0, antenna.x(), antenna.y(), antenna.z(), 1.0);
  fix.east_var_m2 = 4.0;  // anisotropic: turned into the grid by the meridian convergence
  auto m = gnssPositionMeasurement(georeference(), fix, o, yaw);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_LT((m->position_m - base).norm(), 1e-3);
  EXPECT_FALSE(m->use_z);
  auto placed = gnssFixInMap(georeference(), fix, 3.0, 1e5);
  ASSERT_TRUE(placed.ok());
  const double g = placed->antenna.convergence_rad;
  EXPECT_GT(std::abs(g), 1e-3);  // zone 17 at 277 km easting: about 2 deg
  EXPECT_NEAR(m->covariance(0, 1), (4.0 - 1.0) * std::cos(g) * std::sin(g), 1e-9);
  EXPECT_NEAR((m->covariance.topLeftCorner<2, 2>().trace()), 5.0, 1e-9);
  o.use_z = true;
  fix.up_var_m2 = NAN;
  EXPECT_FALSE(gnssPositionMeasurement(georeference(), fix, o, yaw).ok());
  o = GnssPositionOptions{};
  o.max_horizontal_sigma_m = 1.5;
  EXPECT_FALSE(gnssPositionMeasurement(georeference(), fix, o, yaw).ok());
}

}  // namespace
}  // namespace gmm_localization
