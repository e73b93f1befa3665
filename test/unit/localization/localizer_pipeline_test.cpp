// LocalizerPipeline on a synthetic street (test/unit/support/synthetic_world.h): a short drive
// with IMU, drifting INS odometry and scans from the true poses. The pipeline must start from a
// configured pose off by metres, stay within tolerance of the truth with delayed matches, drop
// the oldest waiting scans (the nodelet's scan queue, MatchSession) when matching is slower than
// the scan rate, widen its window after rejected matches and recover, and recover from time
// going backwards (a looping bag). Also the search traversal picture (paper Fig. 9).

#include "gmm_localization/core/localization/localizer_pipeline.h"
#include "gmm_localization/core/matching/traversal_image.h"

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/street_map.h"
#include "support/synthetic_world.h"

namespace gmm_localization {
namespace {

double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

constexpr double kT0 = 100.0;        // drive start [s]
constexpr double kSpeed = 5.0;       // [m/s], heading north along the street at x = -18.5
constexpr double kDuration = 6.0;    // [s]
constexpr double kScanPeriod = 0.5;  // [s]

class LocalizerPipelineTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = std::make_unique<testing::SyntheticWorld>(42);
    const GmmMap gmm = world_->buildMap(testing::streetGeometry(), 1);
    map_ = std::make_shared<ChunkMap>(testing::rasterizeStreet(gmm));
  }
  static void TearDownTestSuite() {
    map_.reset();
    world_.reset();
    scans_.clear();
  }

  /// True pose at drive time t (relative to kT0).
  static Pose6 truth(double t) {
    Pose6 p;
    p.x = -18.5;
    p.y = -15.0 + kSpeed * t;
    p.z = world_->ground(p.x, p.y);
    p.yaw = M_PI / 2;
    return p;
  }
  /// INS pose in odom: the true motion with the simulator's default INS errors (0.2% scale,
  /// 0.1 deg heading; docs/simulator.md).
  static Eigen::Isometry3d insPose(double t) {
    const Pose6 a = truth(0.0), b = truth(t);
    const Eigen::Vector3d d(b.x - a.x, b.y - a.y, b.z - a.z);
    const Eigen::AngleAxisd bias(0.1 * M_PI / 180.0, Eigen::Vector3d::UnitZ());
    Pose6 o = a;
    const Eigen::Vector3d p = Eigen::Vector3d(a.x, a.y, a.z) + bias * (1.002 * d);
    o.x = p.x();
    o.y = p.y();
    o.z = p.z();
    o.yaw = b.yaw + 0.1 * M_PI / 180.0;
    return toIsometry(o);
  }
  /// Scans 3..6 see only a flat sheet 25 m up (nothing the map explains), the others the street.
  static PointList scanOrSkyAt(int k) {
    if (k < 3 || k > 6) return scanAt(k);
    PointList sky;
    for (double x = -20; x <= 20; x += 0.5) {
      for (double y = -20; y <= 20; y += 0.5) sky.emplace_back(x, y, 25.0f);
    }
    return sky;
  }
  static const PointList& scanAt(int k) {
    auto it = scans_.find(k);
    if (it == scans_.end()) {
      it = scans_.emplace(k, world_->scan(truth(0.05 + k * kScanPeriod), 35.0, 0.25, 0.02, 500 + k))
               .first;
    }
    return it->second;
  }

  static LocalizerPipelineOptions options() {
    LocalizerPipelineOptions o;
    o.policy.relocalization.max_consecutive_rejections = 3;
    return o;
  }

  /// Feeds IMU (100 Hz), INS odometry (50 Hz) and scans (2 Hz) of the drive in time order,
  /// starting at time offset `epoch`. `scan_points(k)` may replace scan k's points.
  static void drive(LocalizerPipeline& p, double epoch, double latency_s,
                    const std::function<PointList(int)>& scan_points = nullptr) {
    int next_scan = 0;
    for (int i = 0; i <= static_cast<int>(kDuration * 100); ++i) {
      const double t = i * 0.01;
      const double stamp = epoch + t;
      const double scan_t = 0.05 + next_scan * kScanPeriod;
      if (scan_t <= t && scan_t < kDuration) {
        ScanInput s;
        s.stamp_s = epoch + scan_t;
        s.points = scan_points ? scan_points(next_scan) : scanAt(next_scan);
        p.addScan(std::move(s), latency_s);
        ++next_scan;
      }
      ImuMeasurement imu;
      imu.stamp_s = stamp;
      imu.has_orientation = imu.has_angular_velocity = imu.has_linear_acceleration = true;
      imu.orientation = Eigen::AngleAxisd(truth(t).yaw + 0.3, Eigen::Vector3d::UnitZ());
      imu.linear_acceleration_mps2 = Eigen::Vector3d(0, 0, 9.80665);
      p.addImu(imu);
      if (i % 2 == 0) {
        OdometrySample o;
        o.stamp_s = stamp;
        o.odom_T_base = insPose(t);
        o.linear_mps = Eigen::Vector3d(kSpeed * 1.002, 0, 0);
        TwistMeasurement tw;
        tw.stamp_s = stamp;
        tw.linear_mps = o.linear_mps;
        p.addOdometry(o, tw);
      }
    }
    p.flush();
  }

  static void expectNear(const Pose6& a, const Pose6& truth_pose, double tol_xy, double tol_yaw,
                         const std::string& what) {
    EXPECT_LE(std::hypot(a.x - truth_pose.x, a.y - truth_pose.y), tol_xy) << what;
    EXPECT_LE(std::abs(angleDiff(a.yaw, truth_pose.yaw)), tol_yaw) << what;
  }

  /// The drive from a configured pose 2 m off, then again with the same stamps (a looping bag):
  /// the second pass's reports.
  static auto loopTheDrive(LocalizerPipeline& p) {
    p.setMap(map_);
    Pose6 start = truth(0.05);
    start.x += 2.0;
    p.setConfiguredPose(start, true);
    drive(p, kT0, 0.2);
    p.takeReports();
    EXPECT_EQ(p.resets(), 0u);
    drive(p, kT0, 0.2);
    return p.takeReports();
  }

  static std::unique_ptr<testing::SyntheticWorld> world_;
  static std::shared_ptr<const ChunkMap> map_;
  static std::map<int, PointList> scans_;
};
std::unique_ptr<testing::SyntheticWorld> LocalizerPipelineTest::world_;
std::shared_ptr<const ChunkMap> LocalizerPipelineTest::map_;
std::map<int, PointList> LocalizerPipelineTest::scans_;

Pose6 offsetPose(Pose6 p, double dx, double dy, double dyaw) {
  p.x += dx;
  p.y += dy;
  p.yaw += dyaw;
  return p;
}

TEST_F(LocalizerPipelineTest, TracksTheDriveFromAnOffsetConfiguredPoseWithDelayedMatches) {
  auto created = LocalizerPipeline::create(options());
  ASSERT_TRUE(created.ok()) << created.error();
  LocalizerPipeline& p = created.value();
  p.setMap(map_);
  p.setConfiguredPose(offsetPose(truth(0.05), 3.0, -2.0, 0.04), true);
  drive(p, kT0, 0.3);
  const auto reports = p.takeReports();
  ASSERT_EQ(reports.size(), 12u);
  int accepted = 0, replayed = 0;
  for (size_t k = 0; k < reports.size(); ++k) {
    const PipelineScanReport& r = reports[k];
    const std::string what = "scan " + std::to_string(k) + ": " + r.match.reason;
    ASSERT_TRUE(r.match.accepted()) << what;
    ++accepted;
    expectNear(r.match.pose, truth(r.match.stamp_s - kT0), 0.05, 0.003, what);
    EXPECT_NEAR(r.finish_s - r.start_s, 0.3, 1e-9);
    ASSERT_TRUE(r.offered_to_filter);
    EXPECT_TRUE(r.fuse.fused()) << what << " fuse: " << r.fuse.reason;
    replayed += r.fuse.replayed > 0 ? 1 : 0;
    EXPECT_TRUE(r.match.covariance.allFinite());
    if (k == 0) {
      EXPECT_EQ(r.match.prior.source, PriorSource::kConfigured);
      EXPECT_TRUE(r.match.prior.wide);
      EXPECT_DOUBLE_EQ(r.match.window.half_x_m, options().policy.window.wide_half_xy_m);
    } else {
      // Tracking: the EKF posterior carried by odometry, a window from its 3 sigma.
      EXPECT_EQ(r.match.prior.source, PriorSource::kEkf) << what;
      EXPECT_TRUE(r.match.prior.carried_by_odometry) << what;
      EXPECT_FALSE(r.match.prior.wide) << what;
      EXPECT_LT(r.match.window.half_x_m, 3.0) << what;
      expectNear(r.match.prior.pose, truth(r.match.stamp_s - kT0), 0.5, 0.02, what + " (prior)");
    }
  }
  EXPECT_EQ(accepted, 12);
  // Matches arrive 0.3 s after their stamp, after later IMU and odometry: fused late.
  EXPECT_GE(replayed, 10);
  EXPECT_EQ(p.droppedScans(), 0u);
  ASSERT_TRUE(p.filter().active());
  const double t_end = kT0 + kDuration;
  auto s = p.stateAt(t_end);
  ASSERT_TRUE(s.ok()) << s.error();
  const Pose6 est = fromIsometry(s->pose());
  std::printf("final EKF error: %.3f m, %.4f rad\n",
              std::hypot(est.x - truth(kDuration).x, est.y - truth(kDuration).y),
              std::abs(angleDiff(est.yaw, truth(kDuration).yaw)));
  expectNear(est, truth(kDuration), 0.1, 0.005, "final EKF state");
  EXPECT_EQ(p.tracker().mode(), PriorMode::kTracking);
}

TEST_F(LocalizerPipelineTest, DropsStaleScansWhenMatchingIsSlowerThanTheScanRate) {
  // The pipeline models the nodelet's shipped scan queue (session.scan_queue_size 3: scans wait
  // in arrival order, a scan arriving at a full queue drops the oldest), no longer one waiting
  // slot; the single slot is still there with scan_queue_size 1 (checked below).
  for (const int queue_size : {3, 1}) {
    LocalizerPipelineOptions o = options();
    o.session.scan_queue_size = queue_size;
    auto created = LocalizerPipeline::create(o);
    ASSERT_TRUE(created.ok());
    LocalizerPipeline& p = created.value();
    p.setMap(map_);
    p.setConfiguredPose(offsetPose(truth(0.05), 1.0, 1.0, 0.0), true);
    drive(p, kT0, 1.2);  // a match takes 1.2 s, scans every 0.5 s
    const auto reports = p.takeReports();
    const std::string what = "scan_queue_size " + std::to_string(queue_size);
    uint64_t dropped = 0;
    std::vector<int> matched;
    for (const auto& r : reports) {
      dropped += r.dropped_before;
      EXPECT_TRUE(r.match.accepted()) << what << ": " << r.match.reason;
      // A waiting scan starts when the previous one finishes, never before it arrived.
      EXPECT_GE(r.start_s, r.arrival_s) << what;
      matched.push_back(
          static_cast<int>(std::lround((r.match.stamp_s - kT0 - 0.05) / kScanPeriod)));
    }
    EXPECT_EQ(dropped + reports.size(), 12u) << what;
    EXPECT_EQ(dropped, p.droppedScans()) << what;
    for (size_t k = 1; k < reports.size(); ++k) {
      EXPECT_GE(reports[k].start_s, reports[k - 1].finish_s) << what;
    }
    if (queue_size == 3) {
      // Scans 3, 4, 6 and 8 were the oldest waiting when the queue was full; the three waiting
      // at the end of the drive are matched by flush().
      EXPECT_EQ(matched, (std::vector<int>{0, 1, 2, 5, 7, 9, 10, 11}));
      EXPECT_EQ(p.droppedScans(), 4u);
    } else {
      EXPECT_GE(p.droppedScans(), 5u);
    }
  }
}

TEST_F(LocalizerPipelineTest, WidensAfterRejectedMatchesAndRecovers) {
  auto created = LocalizerPipeline::create(options());
  ASSERT_TRUE(created.ok());
  LocalizerPipeline& p = created.value();
  p.setMap(map_);
  p.setConfiguredPose(offsetPose(truth(0.05), 0.5, 0.5, 0.0), true);
  // Scans 3..6 see only things the map cannot explain (a flat sheet 25 m up): rejected.
  drive(p, kT0, 0.1, scanOrSkyAt);
  const auto reports = p.takeReports();
  ASSERT_EQ(reports.size(), 12u);
  for (int k = 0; k < 12; ++k) {
    const MatchReport& m = reports[k].match;
    const std::string what = "scan " + std::to_string(k) + ": " + m.reason;
    if (k >= 3 && k <= 6) {
      EXPECT_EQ(m.outcome, MatchOutcome::kRejected) << what;
      // max_consecutive_rejections = 3: the fourth rejected scan searches the wide window.
      EXPECT_EQ(m.prior.wide, k == 6) << what;
    } else {
      EXPECT_TRUE(m.accepted()) << what;
      expectNear(m.pose, truth(m.stamp_s - kT0), 0.05, 0.003, what);
      // After the rejections the window is wide until a match is accepted.
      EXPECT_EQ(m.prior.wide, k == 0 || k == 7) << what;
    }
  }
  EXPECT_EQ(reports[6].match.window.half_x_m, options().policy.window.wide_half_xy_m);
  EXPECT_LT(reports[8].match.window.half_x_m, 3.0);
  EXPECT_EQ(p.tracker().mode(), PriorMode::kTracking);
}

TEST_F(LocalizerPipelineTest, TheGlobalSearchRunsBesideTheWorkerAndTheScansMeanwhileAreAnswered) {
  // Scans 3..6 see only a flat sheet 25 m up: three rejected tracking windows, then a rejected
  // wide one makes the localization lost (lost_after_wide_rejections 1). Scan 7 is searched
  // globally, which takes 1.9 s; the scans that arrive meanwhile are answered at once as skipped
  // (the estimate is not trusted), none waits for the search nor is dropped, and the global
  // match is fused when it finishes, after them.
  LocalizerPipelineOptions o = options();
  o.policy.window.global_max_half_xy_m = 20.0;
  o.global_search_latency_s = 1.9;
  auto created = LocalizerPipeline::create(o);
  ASSERT_TRUE(created.ok()) << created.error();
  LocalizerPipeline& p = created.value();
  p.setMap(map_);
  p.setConfiguredPose(offsetPose(truth(0.05), 0.5, 0.5, 0.0), true);
  drive(p, kT0, 0.1, scanOrSkyAt);
  const auto reports = p.takeReports();
  ASSERT_EQ(reports.size(), 12u);
  EXPECT_EQ(p.droppedScans(), 0u);
  std::map<int, const PipelineScanReport*> by_scan;
  std::vector<int> completion;
  for (const auto& r : reports) {
    const int k = static_cast<int>(std::lround((r.match.stamp_s - kT0 - 0.05) / kScanPeriod));
    by_scan[k] = &r;
    completion.push_back(k);
  }
  ASSERT_EQ(by_scan.size(), 12u);
  // The global match (scan 7) completes after the three skipped scans that arrived while it ran.
  EXPECT_EQ(completion, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 8, 9, 10, 7, 11}));
  for (int k = 3; k <= 6; ++k) {
    EXPECT_EQ(by_scan[k]->match.outcome, MatchOutcome::kRejected) << k;
  }
  EXPECT_EQ(by_scan[6]->match.mode_after, PriorMode::kLost);
  const PipelineScanReport& global = *by_scan[7];
  EXPECT_TRUE(global.match.prior.lost);
  EXPECT_NEAR(global.finish_s - global.start_s, 1.9, 1e-9);
  ASSERT_TRUE(global.match.accepted()) << global.match.reason;
  expectNear(global.match.pose, truth(global.match.stamp_s - kT0), 0.05, 0.003, "global");
  EXPECT_TRUE(global.fuse.fused()) << global.fuse.reason;
  for (int k = 8; k <= 10; ++k) {
    const PipelineScanReport& r = *by_scan[k];
    EXPECT_EQ(r.match.outcome, MatchOutcome::kSkipped) << k;
    EXPECT_NE(r.match.reason.find("global search of an earlier scan is running"), std::string::npos)
        << r.match.reason;
    EXPECT_EQ(r.match.mode_after, PriorMode::kLost) << k;
    // Answered when it arrived, not after the global search.
    EXPECT_NEAR(r.finish_s, r.arrival_s, 1e-9) << k;
    EXPECT_LT(r.finish_s, global.finish_s) << k;
  }
  // After the jump: tracking around the EKF, which fused the global match.
  const PipelineScanReport& last = *by_scan[11];
  ASSERT_TRUE(last.match.accepted()) << last.match.reason;
  EXPECT_FALSE(last.match.prior.lost);
  expectNear(last.match.pose, truth(last.match.stamp_s - kT0), 0.05, 0.003, "after");
  EXPECT_EQ(p.tracker().mode(), PriorMode::kTracking);
}

TEST_F(LocalizerPipelineTest, AMeasuredGlobalSearchTakesItsOwnTimeOnTheVirtualClock) {
  // As above, with global_search_latency_measured and a clock that advances 0.2 s at each
  // reading: the global search's finish is its start plus its own measured time, not the
  // fixed 1.9 s nor the scan's latency.
  LocalizerPipelineOptions o = options();
  o.policy.window.global_max_half_xy_m = 20.0;
  o.global_search_latency_s = 1.9;
  o.global_search_latency_measured = true;
  auto ticks = std::make_shared<double>(0.0);
  o.clock = [ticks]() { return *ticks += 0.2; };
  auto created = LocalizerPipeline::create(o);
  ASSERT_TRUE(created.ok()) << created.error();
  LocalizerPipeline& p = created.value();
  p.setMap(map_);
  p.setConfiguredPose(offsetPose(truth(0.05), 0.5, 0.5, 0.0), true);
  drive(p, kT0, 0.1, scanOrSkyAt);
  int global = 0;
  for (const auto& r : p.takeReports()) {
    if (!r.match.prior.lost || r.match.outcome == MatchOutcome::kSkipped) continue;
    ++global;
    EXPECT_GT(r.match.total_s, 0.0);
    EXPECT_NEAR(r.finish_s - r.start_s, r.match.total_s, 1e-9);
    EXPECT_GT(std::abs(r.finish_s - r.start_s - 1.9), 0.01);
  }
  EXPECT_GE(global, 1);
}

TEST_F(LocalizerPipelineTest, RecoversWhenTimeGoesBackwards) {
  auto created = LocalizerPipeline::create(options());
  ASSERT_TRUE(created.ok());
  LocalizerPipeline& p = created.value();
  const auto reports = loopTheDrive(p);  // the same drive, 6 s earlier
  EXPECT_EQ(p.resets(), 1u);
  EXPECT_EQ(p.filter().stops(), 1u);
  ASSERT_FALSE(reports.empty());
  // The first pass's match at the first scan's stamp centres the wide window (not the
  // configured pose 2 m off, nor nothing).
  EXPECT_EQ(reports.front().match.prior.source, PriorSource::kPreviousMatch);
  EXPECT_TRUE(reports.front().match.prior.wide);
  EXPECT_NEAR(reports.front().match.prior.pose.x, truth(0.0).x, 0.1);
  int accepted = 0;
  for (const auto& r : reports) {
    if (!r.match.accepted()) continue;
    ++accepted;
    expectNear(r.match.pose, truth(r.match.stamp_s - kT0), 0.05, 0.003, r.match.reason);
  }
  EXPECT_GE(accepted, 11);
  ASSERT_TRUE(p.filter().active());
  auto s = p.stateAt(kT0 + kDuration);
  ASSERT_TRUE(s.ok());
  expectNear(fromIsometry(s->pose()), truth(kDuration), 0.1, 0.005, "final EKF state");
}

TEST_F(LocalizerPipelineTest, WithoutAMatchHistoryTimeGoingBackwardsReArmsTheConfiguredPose) {
  auto o = options();
  o.policy.relocalization.match_history_s = 0.0;
  auto created = LocalizerPipeline::create(o);
  ASSERT_TRUE(created.ok());
  LocalizerPipeline& p = created.value();
  const auto reports = loopTheDrive(p);
  EXPECT_EQ(p.resets(), 1u);
  ASSERT_FALSE(reports.empty());
  EXPECT_EQ(reports.front().match.prior.source, PriorSource::kConfigured);
}

TEST_F(LocalizerPipelineTest, ReportsWhyNothingIsSearched) {
  auto created = LocalizerPipeline::create(options());
  ASSERT_TRUE(created.ok());
  LocalizerPipeline& p = created.value();
  ScanInput s;
  s.stamp_s = kT0;
  s.points = scanAt(0);
  p.addScan(s, 0.0);  // no prior, no map
  s.stamp_s += 0.5;
  p.setConfiguredPose(truth(0.05), true);
  p.addScan(s, 0.0);  // no map
  p.setMap(map_);
  s.stamp_s += 0.5;
  s.points.assign(100, Eigen::Vector3f::Constant(NAN));
  p.addScan(s, 0.0);  // no finite point
  p.flush();
  const auto r = p.takeReports();
  ASSERT_EQ(r.size(), 3u);
  EXPECT_NE(r[0].match.reason.find("no prior"), std::string::npos) << r[0].match.reason;
  EXPECT_NE(r[1].match.reason.find("no map"), std::string::npos) << r[1].match.reason;
  EXPECT_NE(r[2].match.reason.find("no finite points"), std::string::npos) << r[2].match.reason;
  EXPECT_EQ(r[2].match.dropped_nonfinite, 100u);
  for (const auto& x : r) EXPECT_EQ(x.match.outcome, MatchOutcome::kSkipped);
  EXPECT_FALSE(p.filter().active());
}

// ---- Traversal picture --------------------------------------------------------------------

TEST(RenderTraversal, TilesPerLayerAndHeadingWithTheOptimumMarked) {
  SearchWindow w;
  w.half_x = w.half_y = 4;  // 9 x 9 translations
  w.half_h = 1;             // 3 headings
  std::vector<TraversalNode> nodes;
  for (int j = 0; j < 3; ++j) {
    for (int ty = 0; ty < 9; ty += 8) {
      for (int tx = 0; tx < 9; tx += 8)
        nodes.push_back(
            {3, static_cast<int16_t>(j), static_cast<int16_t>(tx), static_cast<int16_t>(ty), 100});
    }
  }
  nodes.push_back({0, 1, 4, 4, 200});  // the optimum at the base layer
  SearchOutcome best;
  best.heading_index = 1;
  best.tx = 4;
  best.ty = 4;
  const TraversalImage img = renderTraversal(nodes, w, 3, best);
  EXPECT_EQ(img.tile_width, 9);
  EXPECT_EQ(img.width, 3 * 9 + 2 * 2);
  EXPECT_EQ(img.height, 4 * 9 + 3 * 2);
  ASSERT_EQ(img.rgb.size(), static_cast<size_t>(img.width * img.height * 3));
  auto px = [&](int x, int y) { return &img.rgb[3 * (static_cast<size_t>(y) * img.width + x)]; };
  // Layer 3 (top row) is fully painted: low bound colour, not black.
  EXPECT_GT(px(0, 0)[0] + px(0, 0)[1] + px(0, 0)[2], 0);
  // Layer 1 (third row) has no node: black.
  const int y_layer1 = 2 * (9 + 2) + 4;
  EXPECT_EQ(px(2, y_layer1)[0] + px(2, y_layer1)[1] + px(2, y_layer1)[2], 0);
  // Base layer of heading 1: the optimum's cell is white (the cross), the rest black.
  const int x0 = 1 * (9 + 2), y0 = 3 * (9 + 2);
  const uint8_t* c = px(x0 + 4, y0 + 8 - 4);
  EXPECT_EQ(c[0], 255);
  EXPECT_EQ(c[1], 255);
  EXPECT_EQ(px(x0 + 0, y0 + 0)[0], 0);
  EXPECT_TRUE(renderTraversal({}, w, 3, best).rgb.empty());
}

}  // namespace
}  // namespace gmm_localization
