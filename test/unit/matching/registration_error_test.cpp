// Registration failures carry their kind (RegistrationError) beside the unchanged message, and
// MatchProcessor decides "skipped" (nothing to search with) against "rejected" on the kind.

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/street_map.h"
#include "support/synthetic_world.h"

namespace gmm_localization {
namespace {

class RegistrationErrorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = std::make_unique<testing::SyntheticWorld>(42);
    gmm_ = std::make_unique<GmmMap>(world_->buildMap(testing::streetGeometry(), 1));
    chunks_ = std::make_unique<ChunkMap>(testing::rasterizeStreet(*gmm_));
    std::mt19937 rng(5);
    truth_ = world_->streetPose(rng);
    scan_ = world_->scan(truth_, 30.0, 0.3, 0.0, 1);
  }
  static void TearDownTestSuite() {
    chunks_.reset();
    gmm_.reset();
    world_.reset();
  }
  static MatchRequest request() {
    MatchRequest req;
    req.prior = truth_;
    req.half_x_m = req.half_y_m = 1.0;
    req.half_heading_rad = 0.02;
    return req;
  }
  static std::unique_ptr<testing::SyntheticWorld> world_;
  static std::unique_ptr<GmmMap> gmm_;
  static std::unique_ptr<ChunkMap> chunks_;
  static Pose6 truth_;
  static PointList scan_;
};
std::unique_ptr<testing::SyntheticWorld> RegistrationErrorTest::world_;
std::unique_ptr<GmmMap> RegistrationErrorTest::gmm_;
std::unique_ptr<ChunkMap> RegistrationErrorTest::chunks_;
Pose6 RegistrationErrorTest::truth_;
PointList RegistrationErrorTest::scan_;

TEST_F(RegistrationErrorTest, EachFailureHasItsKindAndItsMessage) {
  const Registration reg{RegistrationOptions()};
  const auto ok = reg.match(*chunks_, scan_, request());
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(ok.errorKind(), RegistrationError::kNone);

  const PointList nans(500, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  const auto none = reg.match(*chunks_, nans, request());
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.errorKind(), RegistrationError::kNoPoints) << none.error();
  EXPECT_EQ(none.error().rfind("no points left after filtering: 500 input, 500 non-finite", 0), 0u)
      << none.error();
  EXPECT_EQ(reg.match(*chunks_, {}, request()).errorKind(), RegistrationError::kNoPoints);
  EXPECT_EQ(reg.prepare(*chunks_, {}, request()).errorKind(), RegistrationError::kNoPoints);

  MatchRequest far = request();
  far.prior.x += 10000.0;
  const auto off = reg.match(*chunks_, scan_, far);
  EXPECT_EQ(off.errorKind(), RegistrationError::kOffMap);
  EXPECT_EQ(off.error().rfind("off the map", 0), 0u) << off.error();

  MatchRequest nan_prior = request();
  nan_prior.prior.yaw = std::numeric_limits<double>::quiet_NaN();
  const auto bad_prior = reg.match(*chunks_, scan_, nan_prior);
  EXPECT_EQ(bad_prior.errorKind(), RegistrationError::kInvalidPrior);
  EXPECT_EQ(bad_prior.error(), "prior pose is not finite");

  MatchRequest negative = request();
  negative.half_x_m = -1.0;
  const auto bad_window = reg.match(*chunks_, scan_, negative);
  EXPECT_EQ(bad_window.errorKind(), RegistrationError::kInvalidWindow);
  EXPECT_EQ(bad_window.error().rfind("search window: window half sizes", 0), 0u)
      << bad_window.error();

  RegistrationOptions invalid;
  invalid.heading_step_rad = 0.0;
  const auto bad_options = Registration(invalid).match(*chunks_, scan_, request());
  EXPECT_EQ(bad_options.errorKind(), RegistrationError::kInvalidOptions);
  EXPECT_EQ(bad_options.error().rfind("registration options: heading_step_rad", 0), 0u)
      << bad_options.error();

  // Coverage: a scan twice as large as the world around it cannot lie over mapped cells.
  RegistrationOptions strict;
  strict.min_map_coverage = 1.0;
  PointList wide = scan_;
  for (Eigen::Vector3f& p : wide) p.head<2>() *= 4.0f;
  const auto low = Registration(strict).match(*chunks_, wide, request());
  ASSERT_FALSE(low.ok());
  EXPECT_EQ(low.errorKind(), RegistrationError::kLowCoverage) << low.error();
  EXPECT_NE(low.error().find("% of the scan lies over mapped cells"), std::string::npos)
      << low.error();

  // A global window (the full turn) whose caller no longer wants the answer, and its budget.
  MatchRequest global = request();
  global.half_heading_rad = M_PI;
  std::atomic<bool> cancel{true};
  global.cancel = &cancel;
  const auto cancelled = reg.match(*chunks_, scan_, global);
  EXPECT_EQ(cancelled.errorKind(), RegistrationError::kCancelled) << cancelled.error();
  EXPECT_EQ(cancelled.error().rfind("global search cancelled after ", 0), 0u) << cancelled.error();
  RegistrationOptions tiny;
  tiny.global.max_evaluations = 3;
  global.cancel = nullptr;
  const auto budget = Registration(tiny).match(*chunks_, scan_, global);
  EXPECT_EQ(budget.errorKind(), RegistrationError::kSearchBudget) << budget.error();
  // A score floor no pose can reach (above the map's ceiling): proved, and said, not a budget.
  RegistrationOptions high;
  high.global.min_score_per_point = 100.0;
  const auto below = Registration(high).match(*chunks_, scan_, global);
  EXPECT_EQ(below.errorKind(), RegistrationError::kBelowFloor) << below.error();
  EXPECT_EQ(below.error().rfind("no pose of the window scores the global search's floor of "
                                "100.00 nats per point",
                                0),
            0u)
      << below.error();
  EXPECT_STREQ(registrationErrorName(RegistrationError::kBelowFloor), "below_floor");
  EXPECT_STREQ(registrationErrorName(RegistrationError::kCancelled), "cancelled");

  // The kind survives a conversion to the plain Result (the message does).
  const Result<MatchResult> plain = off;
  EXPECT_EQ(plain.error(), off.error());
  EXPECT_STREQ(registrationErrorName(RegistrationError::kNoPoints), "no_points");
}

TEST_F(RegistrationErrorTest, MatchProcessorSkipsOnNoPointsAndRejectsOtherFailures) {
  auto processor = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions());
  ASSERT_TRUE(processor.ok()) << processor.error();
  Prior prior;
  prior.pose = truth_;
  prior.covariance_xyh = Eigen::Matrix3d::Identity() * 0.01;
  prior.source = PriorSource::kEkf;
  ASSERT_TRUE(prior.valid());

  // Every point finite but outside the range band: registration has no points left.
  ScanInput close;
  close.stamp_s = 1.0;
  close.points = PointList(200, Eigen::Vector3f(0.5f, 0.0f, 0.0f));
  const MatchReport skipped = processor->process(*chunks_, close, prior, nullptr, false);
  EXPECT_EQ(skipped.outcome, MatchOutcome::kSkipped) << skipped.reason;
  EXPECT_EQ(skipped.reason.rfind("no points left after filtering", 0), 0u) << skipped.reason;

  Prior far = prior;
  far.pose.x += 10000.0;
  ScanInput scan;
  scan.stamp_s = 1.0;
  scan.points = scan_;
  const MatchReport rejected = processor->process(*chunks_, scan, far, nullptr, false);
  EXPECT_EQ(rejected.outcome, MatchOutcome::kRejected) << rejected.reason;
  EXPECT_EQ(rejected.reason.rfind("off the map", 0), 0u) << rejected.reason;
  EXPECT_FALSE(rejected.global_window);

  // A global window (the full turn) whose search is cancelled: rejected, and still reported as
  // a global window (the status's global_search) although it left no result.
  Prior lost = prior;
  lost.wide = lost.lost = true;
  lost.wide_window = WindowExtent{5.0, 5.0, M_PI};
  std::atomic<bool> cancel{true};
  const MatchReport cancelled =
      processor->process(*chunks_, scan, lost, nullptr, false, nullptr, nullptr, &cancel);
  EXPECT_EQ(cancelled.outcome, MatchOutcome::kRejected) << cancelled.reason;
  EXPECT_EQ(cancelled.reason.rfind("global search cancelled", 0), 0u) << cancelled.reason;
  EXPECT_TRUE(cancelled.global_window);
  EXPECT_FALSE(cancelled.has_result);
}

}  // namespace
}  // namespace gmm_localization
