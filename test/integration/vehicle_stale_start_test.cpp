// rostest of a stale start (test/integration/vehicle_stale_start.test): the replay launch with
// the fixture's initial pose (2.5 m, -2 m and 3 deg off the first ground truth) while the bag
// plays from 3 s in, the vehicle by then about 20 m from that pose, outside the wide window
// searched around it. Nothing wrong may be reported as good, and the stack must find the
// vehicle by itself: the wide windows around the pose fail, the localization is judged lost
// (relocalization/lost_after_wide_rejections) and the global window is searched around the
// pose, carried by the INS odometry meanwhile. Checked at the end of the drive:
//  - the start was stale: the truth at the first searched scan lies outside its window;
//  - every accepted match is within 0.3 m of the truth, and the first one came from a global
//    search;
//  - the last accepted match is certified; the EKF ends within 0.3 m and 1 deg;
//  - no EKF estimate is farther from the truth than max(0.3 m, 3 sigma of its covariance);
//  - nothing non-finite was published.
#include <gtest/gtest.h>
#include <std_srvs/SetBool.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include "rostest_main.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

TEST(VehicleStaleStart, FindsTheVehicleByItselfAndReportsNothingWrongAsGood) {
  ros::NodeHandle nh;
  Outputs outputs(nh, /*subscribe_truth=*/true);
  double end_stamp = NAN, initial_x = NAN, initial_y = NAN;
  ASSERT_TRUE(ros::param::get("~end_stamp", end_stamp));
  ASSERT_TRUE(ros::param::get("~initial_pose/x", initial_x));
  ASSERT_TRUE(ros::param::get("~initial_pose/y", initial_y));

  ASSERT_TRUE(outputs.mapReadySince(0.0, 90.0))
      << "the map server never finished rasterizing around the initial pose";
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", 30000));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
  const ros::WallTime drive_start = ros::WallTime::now();
  DriveRecord drive;
  ASSERT_TRUE(recordDrive(outputs, end_stamp, 120.0, &drive)) << "the bag never reached its end";
  const std::vector<MatchStatus>& st = drive.statuses;
  const Truth& truth = drive.truth;
  ASSERT_FALSE(st.empty()) << "no scan was searched";

  // The start was stale: the first scan's window did not hold the truth. The first scan of the
  // played part may be stamped (at its revolution's start) before the first truth played.
  ASSERT_FALSE(truth.empty()) << "no ground truth was received";
  const auto first_truth = truth.at(std::max(st.front().header.stamp.toSec(), truth.first()));
  ASSERT_TRUE(first_truth.has_value());
  const double stale_m = std::hypot(first_truth->x - initial_x, first_truth->y - initial_y);
  EXPECT_GT(stale_m, st.front().window_half_x_m)
      << "the vehicle was inside the first window: the test does not test a stale start";

  const AcceptedMatches accepted = expectAcceptedWithin(st, truth, kTolXyM);
  const MatchStatus* first_accepted = accepted.first;
  const MatchStatus* last_accepted = accepted.last;
  std::printf(
      "[vehicle_stale_start] %.1f m stale; %zu statuses, %zu accepted, first accepted %.1f s "
      "after the first scan played (global search %d, certified %d), worst accepted match %.3f m; "
      "drive replayed in %.1f s wall\n",
      stale_m, st.size(), accepted.count,
      first_accepted ? first_accepted->header.stamp.toSec() - st.front().header.stamp.toSec() : NAN,
      first_accepted ? static_cast<int>(first_accepted->global_search) : -1,
      first_accepted ? static_cast<int>(first_accepted->certified) : -1, accepted.worst_m,
      (ros::WallTime::now() - drive_start).toSec());
  ASSERT_NE(first_accepted, nullptr) << "never relocalized";
  EXPECT_TRUE(first_accepted->global_search) << "the first accepted match was not a global search";
  EXPECT_TRUE(last_accepted->certified) << last_accepted->certificate_failure;

  // The EKF: never far from the truth with a small covariance; ends localized.
  const double worst_ratio = expectEkfWithinItsSigma(drive.odometry, truth, kTolXyM);
  std::printf("[vehicle_stale_start] EKF: %zu estimates, worst error / max(0.3 m, 3 sigma) %.2f\n",
              drive.odometry.size(), worst_ratio);
  expectEndsLocalized(outputs, truth, "vehicle_stale_start", kTolXyM, kTolYawRad);
  expectNothingNonFinite(outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  return gmm_localization::node::runRostestMain(argc, argv, "vehicle_stale_start_test");
}
