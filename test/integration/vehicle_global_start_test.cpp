// rostest of a start with no pose at all (test/integration/vehicle_global_start.test): nobody
// gives a pose; the global start sweeps the matcher's global window over the map until a match
// is accepted. Checked at the end of the drive:
//  - every /initialpose is the global start's: a window centre with 3 sigma = 50 m and an
//    unknown heading (sigma pi);
//  - every accepted match is within 0.3 m of the truth, and the first one came from a global
//    search and is certified;
//  - the EKF published nothing before that first match (a pose without a heading does not start
//    it) and never an estimate farther from the truth than max(0.3 m, 3 sigma);
//  - the global start ends idle (state "localized"), the EKF ends within 0.3 m and 1 deg;
//  - nothing non-finite was published.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <mutex>

#include "rostest_main.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

const char* kStartDiag = "/localization/global_start: global start";

std::mutex poses_mutex;
std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;

void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
  std::lock_guard<std::mutex> lock(poses_mutex);
  poses.push_back(*m);
}

TEST(VehicleGlobalStart, FindsTheVehicleWithNoPoseAndReportsNothingWrongAsGood) {
  ros::NodeHandle nh;
  Outputs outputs(nh, /*subscribe_truth=*/true);
  ros::Subscriber sub = nh.subscribe("/initialpose", 20, onInitialPose);
  double end_stamp = NAN;
  ASSERT_TRUE(ros::param::get("~end_stamp", end_stamp));
  const ros::WallTime begin = ros::WallTime::now();
  DriveRecord drive;
  ASSERT_TRUE(recordDrive(outputs, end_stamp, 180.0, &drive)) << "the bag never reached its end";
  const std::vector<MatchStatus>& st = drive.statuses;
  const Truth& truth = drive.truth;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> sent;
  {
    std::lock_guard<std::mutex> lock(poses_mutex);
    sent = poses;
  }
  ASSERT_FALSE(st.empty()) << "no scan was answered";
  ASSERT_FALSE(truth.empty()) << "no ground truth was received";
  ASSERT_FALSE(sent.empty()) << "the global start sent no window";
  for (const auto& p : sent) {
    EXPECT_NEAR(p.pose.covariance[0], (50.0 / 3.0) * (50.0 / 3.0), 1e-6);
    EXPECT_NEAR(p.pose.covariance[35], M_PI * M_PI, 1e-9);
  }

  const AcceptedMatches accepted = expectAcceptedWithin(st, truth, kTolXyM);
  const MatchStatus* first_accepted = accepted.first;
  size_t no_prior = 0, global = 0;
  for (const MatchStatus& s : st) {
    no_prior += s.prior_mode == "no_prior";
    global += s.global_search;
  }
  std::printf(
      "[vehicle_global_start] %zu windows sent; %zu statuses (%zu without a prior, %zu global "
      "searches), %zu accepted, the first %.1f s of bag time after the first scan (global %d, "
      "certified %d); worst accepted match %.3f m; %.1f s wall\n",
      sent.size(), st.size(), no_prior, global, accepted.count,
      first_accepted ? first_accepted->header.stamp.toSec() - st.front().header.stamp.toSec() : NAN,
      first_accepted ? static_cast<int>(first_accepted->global_search) : -1,
      first_accepted ? static_cast<int>(first_accepted->certified) : -1, accepted.worst_m,
      (ros::WallTime::now() - begin).toSec());
  for (const MatchStatus& s : st) {  // the global searches, as the sweep saw them
    if (!s.global_search) continue;
    std::printf(
        "[vehicle_global_start] global search of the scan at %.1f s around (%.1f, %.1f) "
        "+-%.0f m: %s, %.0f ms\n",
        s.header.stamp.toSec() - st.front().header.stamp.toSec(), s.window_x_m, s.window_y_m,
        s.window_half_x_m, s.accepted ? "accepted" : s.reason.substr(0, 60).c_str(), s.total_ms);
  }
  EXPECT_GT(no_prior, 0u) << "the matcher had a prior from the start: not a start without one";
  if (first_accepted == nullptr) {  // what the matcher said instead, in order, runs merged
    std::string last;
    int run = 0;
    auto flush = [&] {
      if (run > 0) std::printf("  %d x %s\n", run, last.c_str());
    };
    for (const MatchStatus& s : st) {
      const std::string what = s.prior_mode + " / " + s.prior_source + " / window " +
                               std::to_string(static_cast<int>(s.window_half_x_m)) + " m" +
                               (s.global_search ? " global" : "") + ": " + s.reason;
      if (what == last) {
        ++run;
        continue;
      }
      flush();
      last = what;
      run = 1;
    }
    flush();
  }
  ASSERT_NE(first_accepted, nullptr) << "never localized";
  EXPECT_TRUE(first_accepted->global_search) << "the first accepted match was not a global search";
  EXPECT_TRUE(first_accepted->certified) << first_accepted->certificate_failure;
  EXPECT_TRUE(accepted.last->certified) << accepted.last->certificate_failure;

  // The EKF: nothing before the first match, never far from the truth with a small covariance.
  const std::vector<nav_msgs::Odometry>& od = drive.odometry;
  ASSERT_FALSE(od.empty()) << "no EKF odometry";
  EXPECT_GE(od.front().header.stamp.toSec(), first_accepted->header.stamp.toSec() - 1e-6)
      << "the EKF published a pose before the first accepted match";
  const double worst_ratio = expectEkfWithinItsSigma(od, truth, kTolXyM);
  std::printf("[vehicle_global_start] EKF: %zu estimates, worst error / max(0.3 m, 3 sigma) %.2f\n",
              od.size(), worst_ratio);
  EXPECT_EQ(outputs.diagnosticValue(kStartDiag, "state"), "localized");
  std::printf(
      "[vehicle_global_start] global start: %s windows searched, %s before all their "
      "chunks came\n",
      outputs.diagnosticValue(kStartDiag, "windows searched").c_str(),
      outputs.diagnosticValue(kStartDiag, "searched before all their chunks came").c_str());
  expectEndsLocalized(outputs, truth, "vehicle_global_start", kTolXyM, kTolYawRad);
  expectNothingNonFinite(outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  return gmm_localization::node::runRostestMain(argc, argv, "vehicle_global_start_test");
}
