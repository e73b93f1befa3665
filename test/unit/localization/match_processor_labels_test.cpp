// MatchProcessor's deferred obstacle labels (create(..., defer_obstacles = true), what the
// matcher nodelet uses to publish the pose before it labels the points): process() leaves the
// labels out, labelObstacles() then gives the very labels, distances and counts that the
// inline labelling gives, adds its time, and does nothing when there is nothing to label.
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/localization/match_processor.h"
#include "support/street_fixture.h"

namespace gmm_localization {
namespace {

class MatchProcessorLabelsTest : public testing::StreetFixture {
 protected:
  /// A scan of the street from a seeded pose, with a parked van the map does not hold (a
  /// block of points 4-8 m ahead, 0.5-1.7 m up), and a prior 0.4 m and 1 deg off.
  void SetUp() override {
    std::mt19937 rng(7);
    truth_ = world_->streetPose(rng);
    input_.stamp_s = 1.0;
    input_.points = world_->scan(truth_, 30.0, 0.3, 0.0, 3);
    for (int i = 0; i < 400; ++i) {
      input_.points.emplace_back(4.0f + 0.01f * i, 0.5f + 0.002f * i, 0.5f + 0.003f * i);
    }
    prior_.pose = truth_;
    prior_.pose.x += 0.4;
    prior_.pose.yaw += 0.0175;
    prior_.covariance_xyh = Eigen::Matrix3d::Identity() * 0.01;
    prior_.source = PriorSource::kEkf;
    ASSERT_TRUE(prior_.valid());
  }

  MatchReport run(const MatchProcessor& p, const std::function<double()>& now = nullptr) const {
    return p.process(*chunks_, input_, prior_, nullptr, false, now);
  }

  Pose6 truth_;
  ScanInput input_;
  Prior prior_;
};

TEST_F(MatchProcessorLabelsTest, DeferredLabelsEqualTheInlineOnes) {
  auto inline_labels = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions());
  auto deferred =
      MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), {}, true);
  ASSERT_TRUE(inline_labels.ok() && deferred.ok());
  EXPECT_TRUE(deferred->registrationOptions().classify_obstacles) << "as given to create()";

  const MatchReport a = run(*inline_labels);
  ASSERT_TRUE(a.accepted()) << a.reason;
  ASSERT_EQ(a.result.obstacles.label.size(), a.points.size());
  EXPECT_GT(a.result.obstacles.obstacles, 300u) << "the van's points are obstacles";

  double clock = 0.0;
  const auto tick = [&clock] { return clock += 1.0; };  // every reading one second later
  MatchReport b = run(*deferred, tick);
  ASSERT_TRUE(b.accepted()) << b.reason;
  EXPECT_TRUE(b.result.obstacles.label.empty()) << "process() left the labels out";
  EXPECT_EQ(b.result.obstacles.obstacles, 0u);
  EXPECT_EQ(b.result.pose.x, a.result.pose.x);
  EXPECT_EQ(b.result.pose.yaw, a.result.pose.yaw);
  const double total = b.total_s, obstacles_s = b.timing.obstacles_s;

  deferred->labelObstacles(*chunks_, b, tick);
  EXPECT_EQ(b.result.obstacles.label, a.result.obstacles.label);
  EXPECT_EQ(b.result.obstacles.mahalanobis, a.result.obstacles.mahalanobis);
  EXPECT_EQ(b.result.obstacles.obstacles, a.result.obstacles.obstacles);
  EXPECT_EQ(b.result.obstacles.over_empty_cells, a.result.obstacles.over_empty_cells);
  EXPECT_EQ(b.result.obstacles.unclassified, a.result.obstacles.unclassified);
  EXPECT_EQ(b.timing.obstacles_s, obstacles_s + 1.0) << "one tick: the labels' time";
  EXPECT_EQ(b.total_s, total + 1.0);

  // Labelled already: a second call changes nothing, nor does the inline processor's.
  deferred->labelObstacles(*chunks_, b, tick);
  EXPECT_EQ(b.total_s, total + 1.0);
  MatchReport c = a;
  inline_labels->labelObstacles(*chunks_, c, tick);
  EXPECT_EQ(c.total_s, a.total_s);
  EXPECT_EQ(c.result.obstacles.label, a.result.obstacles.label);
}

TEST_F(MatchProcessorLabelsTest, NothingToLabelWithoutAResultOrWithTheLabelsOff) {
  auto deferred =
      MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), {}, true);
  ASSERT_TRUE(deferred.ok());
  Prior far = prior_;
  far.pose.x += 10000.0;  // off the map: rejected without a result
  MatchReport off = deferred->process(*chunks_, input_, far, nullptr, false);
  ASSERT_FALSE(off.has_result) << off.reason;
  deferred->labelObstacles(*chunks_, off);
  EXPECT_TRUE(off.result.obstacles.label.empty());

  RegistrationOptions no_labels;
  no_labels.classify_obstacles = false;
  auto off_too = MatchProcessor::create(no_labels, LocalizationPolicyOptions(), {}, true);
  ASSERT_TRUE(off_too.ok());
  MatchReport r = run(*off_too);
  ASSERT_TRUE(r.accepted()) << r.reason;
  off_too->labelObstacles(*chunks_, r);
  EXPECT_TRUE(r.result.obstacles.label.empty()) << "classify_obstacles off: no labels";
}

}  // namespace
}  // namespace gmm_localization
