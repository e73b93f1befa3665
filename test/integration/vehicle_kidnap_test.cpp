// rostest of a kidnapped vehicle (test/integration/vehicle_kidnap.test): launch/localization.launch
// while this node plays the fixture's drive on sim time (vehicle_test_player.h) from an
// /initialpose near the truth, then splices the bag at kKidnapAt s: the vehicle is back at the
// start of the drive, about 50 m away and turned by 90 deg, while the INS odometry, its TF and
// the IMU orientation carry on as if it had not moved. Nobody helps the stack. Checked:
//  - the kidnap is a real one: the jump is at least 45 m and 60 deg, the stack was tracking;
//  - detected within 5 scans: a status after the kidnap, stamped at most 5 scan periods after
//    it, reports the matcher relocalizing or lost;
//  - relocalized within 10 s of bag time: an accepted match within 0.3 m of the truth,
//    published (its scan stamp plus its latency) at most 10 s after the kidnap;
//  - nothing wrong reported as good: no accepted match after the kidnap farther than 0.3 m from
//    the truth, and none certified farther than its protection level; from the first status
//    that reports the matcher lost (from its publication) until 1 s after the match that found
//    the vehicle was published, every EKF estimate within max(0.3 m, 3 sigma) of the truth
//    (its covariance widened by the status);
//  - the drive ends localized (0.3 m, 1 deg) and nothing non-finite was published.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "rostest_main.h"
#include "vehicle_test_player.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

constexpr double kKidnapAt = 18.5;  ///< bag time of the kidnap [s]
constexpr double kKidnapTo = 0.0;   ///< where the drive goes on from [s]
constexpr double kScanPeriodS = 0.1;
constexpr int kDetectWithinScans = 5;
constexpr double kRelocalizeWithinS = 10.0;
// A scan that arrives while the global search runs is answered (not queued behind it) within
// this [ms]: the tracking rate's latency with room for a loaded machine.
constexpr double kAnswerMeanwhileWithinMs = 1000.0;
// The EKF widens when it has heard the lost status: its estimates from this long after the
// status was published on (delivery and the next IMU step) [s].
constexpr double kHearS = 0.05;
constexpr double kTrackAfterS = 4.0;  ///< bag time played after the relocalization budget

TEST(VehicleKidnap, DetectedAndRelocalizedWithoutAPersonAndNothingWrongReportedAsGood) {
  ros::NodeHandle nh;
  std::string bag;
  ASSERT_TRUE(ros::param::get("~bag", bag));
  Outputs outputs(nh, /*subscribe_truth=*/false);
  Faults faults;
  faults.kidnap_at_s = kKidnapAt;
  faults.kidnap_to_s = kKidnapTo;
  FaultyPlayer player(nh, bag, faults);
  const Truth& truth = player.truth();
  const double t0 = player.start().toSec();
  const double kidnap_s = t0 + kKidnapAt;

  // The jump itself.
  const auto before = truth.at(kidnap_s - 0.05);
  const auto after = truth.at(kidnap_s + 0.05);
  ASSERT_TRUE(before && after);
  const double jump_m = std::hypot(after->x - before->x, after->y - before->y);
  const double turn_rad = std::abs(angleDiff(after->yaw, before->yaw));
  EXPECT_GE(jump_m, 45.0);
  EXPECT_GE(turn_rad, 60.0 * M_PI / 180.0);

  ros::Publisher initialpose_pub =
      nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1, true);
  ASSERT_TRUE(waitFor([&] { return initialpose_pub.getNumSubscribers() > 0; }, 30.0))
      << "nobody subscribes to /initialpose";
  player.publishStartClock();
  ros::WallDuration(0.5).sleep();
  const double since = ros::WallTime::now().toSec();
  {
    Pose6 p = truth.at(t0).value_or(Pose6());
    p.x += 2.0;
    p.y -= 1.5;
    p.yaw += 2.0 * M_PI / 180.0;
    p.z = p.roll = p.pitch = 0.0;  // rviz's 2D Pose Estimate
    geometry_msgs::PoseWithCovarianceStamped msg;
    msg.header.frame_id = "map";
    msg.header.stamp = player.start();
    msg.pose.pose = toMsg(p);
    msg.pose.covariance[0] = msg.pose.covariance[7] = 0.25;
    msg.pose.covariance[35] = 0.0076;
    initialpose_pub.publish(msg);
  }
  ASSERT_TRUE(outputs.mapReadySince(since, 60.0)) << "no map around /initialpose";
  player.play();
  const double stop_rel = kKidnapAt + kRelocalizeWithinS + kTrackAfterS;
  ASSERT_TRUE(waitFor([&] { return player.elapsed() >= stop_rel || player.finished(); }, 180.0))
      << "the player never reached " << stop_rel << " s";
  ros::WallDuration(2.0).sleep();  // the last scans' statuses

  std::vector<MatchStatus> st;
  std::vector<nav_msgs::Odometry> od;
  outputs.locked([&] {
    st = outputs.statuses_;
    od = outputs.odometry_;
    return 0;
  });
  ASSERT_FALSE(st.empty());

  // Tracking before the kidnap.
  size_t accepted_before = 0, before_count = 0;
  for (const MatchStatus& s : st) {
    const double t = s.header.stamp.toSec();
    if (t < kidnap_s - 2.0 || t >= kidnap_s - kScanPeriodS) continue;
    ++before_count;
    accepted_before += s.accepted ? 1 : 0;
  }
  EXPECT_GE(accepted_before, before_count / 2 + 1)
      << "the stack was not tracking before the kidnap";

  // After it (a scan stamped up to a period before the splice may already be the new place).
  // lost_heard_s: when the lost status was published (the EKF cannot widen before it hears it);
  // found_heard_s: when the relocalizing match was.
  double detected_s = NAN, lost_s = NAN, lost_heard_s = NAN, relocalized_s = NAN,
         found_heard_s = NAN;
  const MatchStatus* relocalizing_match = nullptr;
  size_t after_count = 0, accepted_after = 0;
  for (const MatchStatus& s : st) {
    const double t = s.header.stamp.toSec();
    if (t < kidnap_s - kScanPeriodS) continue;
    ++after_count;
    if (std::isnan(detected_s) && (s.prior_mode == "relocalizing" || s.prior_mode == "lost")) {
      detected_s = t;
    }
    if (std::isnan(lost_s) && s.prior_mode == "lost") {
      lost_s = t;
      lost_heard_s = t + 1e-3 * s.latency_ms;
    }
    if (!s.accepted) continue;
    ++accepted_after;
    const PoseError e = poseError(truth, t, toPose(s.pose.pose));
    if (!e.valid()) continue;
    EXPECT_LE(e.xy_m, kTolXyM) << "a match " << e.xy_m << " m off was accepted " << t - kidnap_s
                               << " s after the kidnap (prior " << s.prior_source << ", window "
                               << s.window_half_x_m << " m, certified "
                               << static_cast<int>(s.certified) << " " << s.certificate_failure
                               << ", log-likelihood per point " << s.log_likelihood_per_point
                               << ", coverage " << s.map_coverage << ")";
    if (s.certified) {
      EXPECT_LE(e.xy_m, s.protection_xy_m)
          << "certified beyond its protection level at " << t - kidnap_s << " s after the kidnap";
    }
    if (std::isnan(relocalized_s) && e.xy_m <= kTolXyM) {
      relocalized_s = t;
      found_heard_s = t + 1e-3 * s.latency_ms;
      relocalizing_match = &s;
    }
  }
  std::printf(
      "[vehicle_kidnap] jump %.1f m, %.0f deg; %zu statuses after it, %zu accepted; detected "
      "%.2f s after it, lost at %.2f s (published at %.2f s), relocalized by the scan at %.2f s "
      "(published at %.2f s; global search %d, certified %d)\n",
      jump_m, turn_rad * 180.0 / M_PI, after_count, accepted_after, detected_s - kidnap_s,
      lost_s - kidnap_s, lost_heard_s - kidnap_s, relocalized_s - kidnap_s,
      found_heard_s - kidnap_s,
      relocalizing_match ? static_cast<int>(relocalizing_match->global_search) : -1,
      relocalizing_match ? static_cast<int>(relocalizing_match->certified) : -1);
  if (std::isnan(relocalized_s)) {
    // What the matcher answered after the kidnap, for the diagnosis (all but the scans skipped
    // while a global search ran).
    for (const MatchStatus& s : st) {
      const double t = s.header.stamp.toSec();
      if (t < kidnap_s - kScanPeriodS || s.reason.rfind("not searched", 0) == 0) continue;
      const PoseError e = poseError(truth, t, toPose(s.pose.pose));
      std::printf(
          "[vehicle_kidnap]   scan +%.2f s: %s (%s), prior %s, mode %s, window %.1f m, global %d, "
          "certified %d %s, %.1f m from the truth, latency %.0f ms\n",
          t - kidnap_s, s.accepted ? "accepted" : "not accepted", s.reason.c_str(),
          s.prior_source.c_str(), s.prior_mode.c_str(), s.window_half_x_m,
          static_cast<int>(s.global_search), static_cast<int>(s.certified),
          s.certificate_failure.c_str(), e.valid() ? e.xy_m : NAN, s.latency_ms);
    }
  }
  ASSERT_FALSE(std::isnan(detected_s)) << "the kidnap was never detected";
  EXPECT_LE(detected_s - kidnap_s, kDetectWithinScans * kScanPeriodS + 0.05)
      << "not detected within " << kDetectWithinScans << " scans";
  ASSERT_FALSE(std::isnan(relocalized_s)) << "never relocalized";
  EXPECT_LE(found_heard_s - kidnap_s, kRelocalizeWithinS)
      << "the match that found the vehicle was published too late";

  // While the global search ran (scans stamped after the one it searched, published before its
  // match was): the scans kept being answered (skipped, or searched in the interim window),
  // none waited for the search.
  size_t answered_meanwhile = 0;
  double worst_latency_ms = 0.0;
  for (const MatchStatus& s : st) {
    const double t = s.header.stamp.toSec();
    if (!(t > relocalized_s && t + 1e-3 * s.latency_ms < found_heard_s)) continue;
    ++answered_meanwhile;
    worst_latency_ms = std::max(worst_latency_ms, s.latency_ms);
  }
  std::printf(
      "[vehicle_kidnap] while the global search ran: %zu scans answered, worst latency %.0f ms\n",
      answered_meanwhile, worst_latency_ms);
  EXPECT_GE(answered_meanwhile, 1u) << "no scan was answered while the global search ran";
  EXPECT_LE(worst_latency_ms, kAnswerMeanwhileWithinMs) << "a scan waited for the global search";

  // The EKF from the moment it heard that the matcher was lost (kHearS after the status) until
  // 1 s after the match that found the vehicle was published.
  if (!std::isnan(lost_heard_s)) {
    double worst_ratio = 0.0;
    size_t checked = 0;
    for (const nav_msgs::Odometry& o : od) {
      const double t = o.header.stamp.toSec();
      if (t < lost_heard_s + kHearS || t > found_heard_s + 1.0) continue;
      const PoseError e = poseError(truth, t, toPose(o.pose.pose));
      if (!e.valid()) continue;
      ++checked;
      const double sigma = std::sqrt(o.pose.covariance[0] + o.pose.covariance[7]);
      const double bound = std::max(kTolXyM, 3.0 * sigma);
      worst_ratio = std::max(worst_ratio, e.xy_m / bound);
      EXPECT_LE(e.xy_m, bound) << "EKF estimate " << e.xy_m << " m off with sigma " << sigma
                               << " m, " << t - kidnap_s << " s after the kidnap";
    }
    std::printf(
        "[vehicle_kidnap] EKF while lost: %zu estimates, worst error / max(0.3 m, 3 sigma) %.2f\n",
        checked, worst_ratio);
  }
  expectEndsLocalized(outputs, truth, "vehicle_kidnap", kTolXyM, kTolYawRad);
  expectNothingNonFinite(outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  return gmm_localization::node::runRostestMain(argc, argv, "vehicle_kidnap_test");
}
