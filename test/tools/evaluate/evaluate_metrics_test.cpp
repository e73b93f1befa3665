// The evaluation maths of `evaluate` (src/tools/evaluate/evaluate_metrics.h) on fixed inputs: time
// association with the ground truth, the lateral / longitudinal decomposition, RMS and
// quantiles, precision / recall, the random offsets of Fig. 8, and a summary over no data.
#include "evaluate/evaluate_metrics.h"

#include <cmath>

#include <gtest/gtest.h>

#include "evaluate/evaluate_summary.h"

namespace gmm_localization {
namespace eval {
namespace {

PoseStamped2 pose(double t, double x, double y, double yaw) {
  PoseStamped2 p;
  p.t = t;
  p.x = x;
  p.y = y;
  p.yaw = yaw;
  return p;
}

TEST(EvaluateMetrics, LongitudinalIsAlongTheTruthHeadingAndLateralToItsLeft) {
  // Truth heading north (+y): an estimate 0.3 m further north is 0.3 m ahead; 0.1 m west
  // (-x) is 0.1 m to the left.
  const PoseStamped2 truth = pose(0, 10, 20, M_PI / 2);
  VehicleFrameError e = vehicleFrameError(pose(0, 9.9, 20.3, M_PI / 2 + 0.01), truth);
  EXPECT_NEAR(e.longitudinal_m, 0.3, 1e-12);
  EXPECT_NEAR(e.lateral_m, 0.1, 1e-12);
  EXPECT_NEAR(e.yaw_rad, 0.01, 1e-12);
  EXPECT_NEAR(e.planar_m(), std::hypot(0.3, 0.1), 1e-12);
  // Heading east: behind and to the right.
  e = vehicleFrameError(pose(0, -0.2, -0.05, 0.0), pose(0, 0, 0, 0.0));
  EXPECT_NEAR(e.longitudinal_m, -0.2, 1e-12);
  EXPECT_NEAR(e.lateral_m, -0.05, 1e-12);
  // Heading 30 deg: an error of (cos 30, sin 30) is purely longitudinal.
  const double a = M_PI / 6;
  e = vehicleFrameError(pose(0, std::cos(a), std::sin(a), a), pose(0, 0, 0, a));
  EXPECT_NEAR(e.longitudinal_m, 1.0, 1e-12);
  EXPECT_NEAR(e.lateral_m, 0.0, 1e-12);
}

TEST(EvaluateMetrics, HeadingErrorWrapsAcrossPi) {
  const VehicleFrameError e = vehicleFrameError(pose(0, 0, 0, -M_PI + 0.02), pose(0, 0, 0, M_PI));
  EXPECT_NEAR(e.yaw_rad, 0.02, 1e-12);
  EXPECT_NEAR(wrapAngle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrapAngle(-3 * M_PI / 2), M_PI / 2, 1e-12);
}

TEST(EvaluateMetrics, RmsMeanAbsAndQuantiles) {
  EXPECT_DOUBLE_EQ(rms({3.0, -4.0}), std::sqrt(12.5));
  EXPECT_TRUE(std::isnan(rms({}))) << "no data is no data, not 0 m";
  EXPECT_TRUE(std::isnan(meanAbs({})));
  EXPECT_DOUBLE_EQ(meanAbs({1.0, -3.0}), 2.0);
  EXPECT_DOUBLE_EQ(quantile({4, 1, 3, 2, 5}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(quantile({1, 2, 3, 4, 5}, 0.95), 4.8);  // 1 + 0.95 * 4 = 4.8
  EXPECT_DOUBLE_EQ(quantile({7}, 0.3), 7.0);
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));

  std::vector<VehicleFrameError> errors(4);
  errors[0].longitudinal_m = 0.1;
  errors[1].longitudinal_m = -0.1;
  errors[2].lateral_m = 0.2;
  errors[3].lateral_m = 0.0;
  const ErrorSummary s = summarize(errors);
  EXPECT_EQ(s.count, 4u);
  EXPECT_NEAR(s.rms_longitudinal_m, std::sqrt(0.02 / 4), 1e-12);
  EXPECT_NEAR(s.rms_lateral_m, std::sqrt(0.04 / 4), 1e-12);
  EXPECT_NEAR(s.max_planar_m, 0.2, 1e-12);
}

TEST(EvaluateMetrics, PrecisionAndRecall) {
  Confusion c;
  // 3 true obstacles (2 found), 5 map points (1 called obstacle).
  for (bool found : {true, true, false}) c.add(found, true);
  for (bool called : {true, false, false, false, false}) c.add(called, false);
  EXPECT_EQ(c.tp, 2u);
  EXPECT_EQ(c.fn, 1u);
  EXPECT_EQ(c.fp, 1u);
  EXPECT_EQ(c.tn, 4u);
  EXPECT_DOUBLE_EQ(c.precision(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(c.recall(), 2.0 / 3.0);
  Confusion d;
  d.add(false, false);
  EXPECT_TRUE(std::isnan(d.precision()));  // nothing predicted
  EXPECT_TRUE(std::isnan(d.recall()));     // nothing to find
  d += c;
  EXPECT_EQ(d.total(), 9u);
  EXPECT_EQ(d.tn, 5u);
}

TEST(EvaluateMetrics, TrajectoryInterpolatesAtTheEstimateStamp) {
  Trajectory t;
  ASSERT_TRUE(t.add(pose(10.0, 0, 0, M_PI - 0.1)));
  ASSERT_TRUE(t.add(pose(10.1, 1, 2, -M_PI + 0.1)));  // heading crosses +-pi
  ASSERT_TRUE(t.add(pose(10.5, 2, 2, 0.0)));
  EXPECT_FALSE(t.add(pose(10.5, 9, 9, 0.0)));  // not newer: ignored
  auto p = t.at(10.025, 0.2);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x, 0.25, 1e-9);
  EXPECT_NEAR(p->y, 0.5, 1e-9);
  EXPECT_NEAR(p->yaw, M_PI - 0.05, 1e-9);  // the short way round, not through 0
  p = t.at(10.1, 0.2);                     // exactly on a sample
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->x, 1.0);
  EXPECT_FALSE(t.at(9.99, 0.2).has_value());   // before the truth
  EXPECT_FALSE(t.at(10.51, 0.2).has_value());  // after it
  EXPECT_FALSE(t.at(10.3, 0.2).has_value());   // the 0.4 s gap is not bridged
  EXPECT_TRUE(t.at(10.3, 0.5).has_value());
}

TEST(EvaluateMetrics, OffsetsAreUniformOverTheDiscAndReproducible) {
  OffsetSampler a(7, 10.0, 0.25), b(7, 10.0, 0.25), other(8, 10.0, 0.25);
  int inner = 0, left = 0;
  double max_r = 0.0, max_yaw = 0.0;
  bool differs = false;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const PlanarOffset o = a.next();
    const PlanarOffset p = b.next();
    EXPECT_EQ(o.dx_m, p.dx_m);
    EXPECT_EQ(o.dyaw_rad, p.dyaw_rad);
    differs |= other.next().dx_m != o.dx_m;
    max_r = std::max(max_r, o.distance_m());
    max_yaw = std::max(max_yaw, std::abs(o.dyaw_rad));
    inner += o.distance_m() < 10.0 / std::sqrt(2.0) ? 1 : 0;  // half of the disc's area
    left += o.dx_m < 0 ? 1 : 0;
  }
  EXPECT_TRUE(differs);
  EXPECT_LE(max_r, 10.0);
  EXPECT_GT(max_r, 9.9);
  EXPECT_LE(max_yaw, 0.25);
  EXPECT_NEAR(inner / double(n), 0.5, 0.02);
  EXPECT_NEAR(left / double(n), 0.5, 0.02);
}

TEST(EvaluateSummary, CountsMatchesRateLatencyOffsetSuccessAndLocalizedSamples) {
  EvaluationResults r;
  r.info.duration_s = 2.0;
  r.info.scans_in_bag = 20;
  for (int i = 0; i < 6; ++i) {
    MatchRow m;
    m.stamp_s = i * 0.1;
    m.outcome = i < 5 ? "accepted" : "rejected";
    m.fuse = i < 4 ? "fused" : (i == 4 ? "rejected_gate" : "");
    m.latency_s = 0.2 + 0.01 * i;
    m.total_ms = 50.0 + i;
    m.has_pose = i < 5;
    m.error.longitudinal_m = i < 5 ? 0.1 : 5.0;  // the rejected one does not count
    r.matches.push_back(m);
  }
  for (double e : {0.1, 0.2, 0.6, 0.3}) {
    OffsetRow o;
    o.has_result = true;
    o.error_m = e;
    o.accepted = e < 0.5;
    r.offsets.push_back(o);
  }
  OffsetRow failed;  // no result: a failure
  r.offsets.push_back(failed);
  for (int i = 0; i < 4; ++i) {
    EkfRow e;
    e.sigma_x_m = e.sigma_y_m = i == 0 ? 12.0 : 0.1;  // the first: not localized yet
    e.error.longitudinal_m = i == 0 ? 5.0 : 0.02;
    r.ekf.push_back(e);
  }
  const Summary s = summarizeResults(r);
  EXPECT_NEAR(s.ekf.rms_longitudinal_m, std::sqrt((25.0 + 3 * 0.0004) / 4), 1e-12);
  EXPECT_NEAR(s.ekf_localized.rms_longitudinal_m, 0.02, 1e-12);
  EXPECT_EQ(s.ekf_unlocalized, 1u);
  EXPECT_EQ(s.accepted, 5u);
  EXPECT_EQ(s.fused, 4u);
  EXPECT_EQ(s.processed, 6u);
  EXPECT_DOUBLE_EQ(s.match_rate_hz, 2.5);
  EXPECT_DOUBLE_EQ(s.accepted_share, 0.25);
  EXPECT_NEAR(s.raw.rms_longitudinal_m, 0.1, 1e-12);
  EXPECT_EQ(s.raw.count, 5u);
  EXPECT_NEAR(s.latency_s.p50, 0.22, 1e-12);
  EXPECT_DOUBLE_EQ(s.offset_success, 3.0 / 5.0);
  EXPECT_DOUBLE_EQ(s.offset_accepted, 3.0 / 5.0);
}

TEST(EvaluateSummary, AnEvaluationOverNoDataSaysSoAndReportsNoRms) {
  EvaluationResults r;
  r.info.mode = "bag";
  r.info.dataset = "downtown";
  r.info.duration_s = 10.0;
  MatchRow rejected;
  rejected.outcome = "rejected";
  rejected.total_ms = 40.0;
  r.matches.assign(3, rejected);
  Summary s = summarizeResults(r);
  const std::string reason = noDataReason(r, s);
  EXPECT_NE(reason.find("no data"), std::string::npos) << reason;
  EXPECT_NE(reason.find("0 accepted of 3 scans"), std::string::npos) << reason;
  const std::string md = summaryMarkdown(r, s);
  EXPECT_NE(md.find("**No data**"), std::string::npos) << md;
  EXPECT_EQ(md.find(" 0.0 cm"), std::string::npos) << "an RMS over zero samples:\n" << md;
  EXPECT_EQ(md.find("| 0.00 cm"), std::string::npos) << md;
  const std::string json = summaryJson(r, s);
  EXPECT_NE(json.find("\"no_data\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"count\": 0, \"rms_longitudinal_m\": null"), std::string::npos) << json;

  // One EKF sample against the truth is something to score; the empty raw series alone is
  // reported as none.
  EkfRow e;
  e.error.longitudinal_m = 0.03;
  e.error.lateral_m = -0.02;
  r.ekf.push_back(e);
  s = summarizeResults(r);
  EXPECT_EQ(noDataReason(r, s), "");
  EXPECT_NE(summaryJson(r, s).find("\"no_data\": false"), std::string::npos);
  EXPECT_EQ(summaryMarkdown(r, s).find("**No data**"), std::string::npos);
  EXPECT_NEAR(s.ekf.rms_longitudinal_m, 0.03, 1e-12);
  EXPECT_TRUE(std::isnan(s.raw.rms_longitudinal_m));
}

}  // namespace
}  // namespace eval
}  // namespace gmm_localization
