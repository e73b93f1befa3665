// rostest of the fused method through the vehicle launch (test/integration/vehicle_fused.test):
// replay.launch method:=fused starts a second map server for MAP/reflectivity beside the height
// one; the matcher searches both layers at once. The player starts paused; this node resumes it
// once both map servers have rasterized the map around the initial pose (and the matcher holds
// both layers), plays the first seconds of the drive, then checks:
//  - the second map server is up on its own topics, the matcher's diagnostics show its layer;
//  - with both layers held, no status says the reflectivity layer is missing; from the first
//    accepted match on (in publication order), 90% are accepted; one status per scan;
//  - every accepted match (the first one, the search around the configured pose, included) lies
//    within 0.3 m of the truth, and the EKF ends within 0.3 m and 1 deg;
//  - nothing non-finite was published.
#include <gtest/gtest.h>
#include <std_srvs/SetBool.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

std::unique_ptr<Outputs> outputs;

bool serverReady(const std::string& server) {
  const std::string name = "/localization/" + server + ": chunks";
  const std::string held = outputs->diagnosticValue(name, "chunks held");
  return outputs->diagnosticValue(name, "chunks pending") == "0" && !held.empty() && held != "0";
}

TEST(VehicleFused, MatchesBothLayersThroughTheLaunch) {
  double start_stamp = NAN, played_s = NAN;
  ASSERT_TRUE(ros::param::get("~start_stamp", start_stamp));
  ASSERT_TRUE(ros::param::get("~played_s", played_s));
  std::string method;
  ASSERT_TRUE(ros::param::get("/localization/matcher/method", method));
  EXPECT_EQ(method, "fused");
  std::string layer;
  ASSERT_TRUE(ros::param::get("/localization/reflectivity_map_server/layer", layer));
  EXPECT_EQ(layer, "reflectivity");

  // 1. Both layers rasterized around the initial pose, and received by the matcher.
  const std::string matching = "/localization/matcher: scan matching";
  ASSERT_TRUE(waitFor(
      [&] {
        const std::string held =
            outputs->diagnosticValue(matching, "reflectivity layer: chunks held");
        return serverReady("map_server") && serverReady("reflectivity_map_server") &&
               !held.empty() && held != "0";
      },
      60.0))
      << "the map servers never finished rasterizing, or the matcher never received the "
         "reflectivity layer (reflectivity/map_chunks)";
  const std::string directory =
      outputs->diagnosticValue(matching, "reflectivity layer: map directory");
  EXPECT_TRUE(directory.size() >= 12 &&
              directory.compare(directory.size() - 12, 12, "reflectivity") == 0)
      << "the matcher's reflectivity layer comes from '" << directory << "'";

  // 2. Play the first seconds of the drive.
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", 30000));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
  const ros::WallTime drive_start = ros::WallTime::now();
  ASSERT_TRUE(waitFor(
      [&] {
        return outputs->locked([&] {
          return !outputs->truth_.empty() && outputs->truth_.last() >= start_stamp + played_s - 0.3;
        });
      },
      60.0))
      << "the bag never reached " << played_s << " s";
  ros::WallDuration(2.0).sleep();  // the last scans' statuses
  std::printf("[vehicle_fused] %.0f s of the drive replayed in %.1f s wall\n", played_s,
              (ros::WallTime::now() - drive_start).toSec());

  std::vector<MatchStatus> st;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
  Truth truth;
  outputs->locked([&] {
    st = outputs->statuses_;
    poses = outputs->poses_;
    truth = outputs->truth_;
    return 0;
  });
  uint64_t dropped = 0, accepted = 0;
  std::vector<double> total_ms, search_ms;
  std::map<std::string, int> reasons;  // of the scans not accepted (printed)
  for (const MatchStatus& s : st) {
    if (!s.accepted) ++reasons[s.reason.substr(0, 70)];
    dropped += s.dropped_scans;
    accepted += s.accepted ? 1 : 0;
    EXPECT_EQ(s.reason.find("reflectivity layer"), std::string::npos)
        << "a scan after both layers arrived: " << s.reason;
    if (s.accepted) {
      total_ms.push_back(s.total_ms);
      search_ms.push_back(s.search_ms);
    }
  }
  // One status per scan (the global worker's may come after the interim ones of later scans).
  std::vector<ros::Time> stamps;
  for (const MatchStatus& s : st) stamps.push_back(s.header.stamp);
  std::sort(stamps.begin(), stamps.end());
  EXPECT_EQ(std::adjacent_find(stamps.begin(), stamps.end()), stamps.end())
      << "a scan answered twice";
  ASSERT_GE(st.size(), 20u) << "too few scans answered in " << played_s << " s";
  // The first search (3.2 m off, the wide window) may end uncertified at its node budget; the
  // global search then finds the vehicle (the scans meanwhile answered, not searched). From the
  // first accepted match on, the fused matcher tracks.
  const auto first =
      std::find_if(st.begin(), st.end(), [](const MatchStatus& s) { return s.accepted; });
  ASSERT_NE(first, st.end()) << "no fused match accepted";
  const size_t tracking = static_cast<size_t>(st.end() - first);
  const size_t tracked = static_cast<size_t>(
      std::count_if(first, st.end(), [](const MatchStatus& s) { return s.accepted; }));
  std::printf(
      "[vehicle_fused] first accepted match (publication order): the scan at +%.2f s (prior "
      "%s); %zu of the %zu "
      "statuses from it on accepted\n",
      first->header.stamp.toSec() - start_stamp, first->prior_source.c_str(), tracked, tracking);
  EXPECT_LE(first->header.stamp.toSec() - start_stamp, 4.0) << "acquisition too slow";
  EXPECT_GE(tracked, 9 * tracking / 10) << "fewer than 90% of the tracking scans matched";
  EXPECT_GE(tracking, 30u) << "too few scans answered after the first match";

  // Accepted matches against the truth.
  std::vector<double> xy;
  double max_yaw = 0.0;
  for (const auto& p : poses) {
    const PoseError e = poseError(truth, p.header.stamp.toSec(), toPose(p.pose.pose));
    if (!e.valid()) continue;
    xy.push_back(e.xy_m);
    max_yaw = std::max(max_yaw, e.yaw_rad);
  }
  ASSERT_FALSE(xy.empty()) << "no accepted fused match within the truth's time span";
  std::sort(xy.begin(), xy.end());
  std::sort(total_ms.begin(), total_ms.end());
  std::sort(search_ms.begin(), search_ms.end());
  std::printf(
      "[vehicle_fused] %zu statuses, %lu dropped, %lu accepted; match error median %.3f m, "
      "max %.3f m, yaw max %.3f deg; total_ms median %.0f, max %.0f; search_ms median %.0f\n",
      st.size(), static_cast<unsigned long>(dropped), static_cast<unsigned long>(accepted),
      xy[xy.size() / 2], xy.back(), max_yaw * 180.0 / M_PI,
      total_ms.empty() ? 0.0 : total_ms[total_ms.size() / 2],
      total_ms.empty() ? 0.0 : total_ms.back(),
      search_ms.empty() ? 0.0 : search_ms[search_ms.size() / 2]);
  for (const auto& [reason, n] : reasons)
    std::printf("[vehicle_fused] %3d x %s\n", n, reason.c_str());
  EXPECT_LE(xy.back(), kTolXyM) << "an accepted fused match off the truth";
  EXPECT_LE(max_yaw, kTolYawRad);
  expectEndsLocalized(*outputs, truth, "vehicle_fused", kTolXyM, kTolYawRad);
  expectNothingNonFinite(*outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_fused_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  gmm_localization::node::outputs =
      std::make_unique<gmm_localization::node::vehicle_test::Outputs>(nh, /*subscribe_truth=*/true);
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  gmm_localization::node::outputs.reset();
  return result;
}
