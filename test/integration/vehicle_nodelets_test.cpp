// rostest of launch/localization.launch with every nodelet (vehicle_nodelets.test): the four
// nodelets load into one manager, each reports on /diagnostics, the topics between them and
// from the vehicle are wired as docs/ros.md says (checked on the master's graph), and the map
// server's chunks reach the matcher.
#include <gtest/gtest.h>
#include <nodelet/NodeletList.h>
#include <ros/master.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <memory>
#include <set>

#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

const char* kManager = "/localization/localization_manager";
std::unique_ptr<Outputs> outputs;

TEST(VehicleNodelets, AllNodeletsRunInOneManager) {
  ASSERT_TRUE(ros::service::waitForService(std::string(kManager) + "/list", 30000));
  nodelet::NodeletList list;
  const std::set<std::string> expected = {"/localization/map_server", "/localization/matcher",
                                          "/localization/ekf", "/localization/cloud_merger"};
  std::set<std::string> loaded;
  ASSERT_TRUE(waitFor(
      [&] {
        if (!ros::service::call(std::string(kManager) + "/list", list)) return false;
        loaded =
            std::set<std::string>(list.response.nodelets.begin(), list.response.nodelets.end());
        return loaded == expected;
      },
      30.0))
      << "nodelets in " << kManager << ": " << list.response.nodelets.size();

  // Each nodelet reports.
  const std::vector<std::string> diagnostics = {
      "/localization/map_server: map", "/localization/map_server: chunks",
      "/localization/matcher: scan matching", "/localization/ekf: filter",
      "/localization/ekf: inputs"};
  EXPECT_TRUE(waitFor(
      [&] {
        const auto names = outputs->diagnosticNames();
        bool merger = false;
        for (const auto& n : names)
          merger = merger || n.rfind("/localization/cloud_merger", 0) == 0;
        return merger && std::all_of(diagnostics.begin(), diagnostics.end(), [&](const auto& d) {
                 return std::find(names.begin(), names.end(), d) != names.end();
               });
      },
      20.0))
      << "a nodelet never published diagnostics";
}

TEST(VehicleNodelets, TopicsAreWired) {
  Graph g;
  const std::set<std::string> manager = {kManager};
  // Give every subscription time to register.
  ASSERT_TRUE(waitFor(
      [&] {
        g = Graph();
        return readGraph(&g) && g.subscribers["/localization/pose"].count(kManager) == 1 &&
               g.subscribers["/localization/velodyne_points"].count(kManager) == 1;
      },
      20.0));
  // Inside the manager: map server -> matcher, matcher -> EKF -> matcher, merger -> matcher.
  for (const char* topic :
       {"/localization/map_chunks", "/localization/map_index", "/localization/pose",
        "/localization/odometry", "/localization/velodyne_points"}) {
    EXPECT_EQ(g.publishers[topic], manager) << topic;
    EXPECT_EQ(g.subscribers[topic].count(kManager), 1u) << topic;
  }
  // Vehicle inputs (launch args) and rviz's initial pose.
  for (const char* topic : {"/ins/odom", "/imu/data", "/initialpose", "/velodyne_0/velodyne_points",
                            "/velodyne_1/velodyne_points", "/velodyne_2/velodyne_points",
                            "/velodyne_3/velodyne_points"}) {
    EXPECT_EQ(g.subscribers[topic].count(kManager), 1u) << topic;
  }
  // With merge_clouds the matcher reads the merger, not the bag's merged cloud.
  EXPECT_EQ(g.subscribers["/velodyne_points"].count(kManager), 0u);
  for (const char* topic :
       {"/localization/status", "/localization/map_cloud", "/localization/obstacles",
        "/localization/scan_classified", "/localization/search_traversal"}) {
    EXPECT_EQ(g.publishers[topic], manager) << topic;
  }
  EXPECT_TRUE(ros::service::exists("/localization/relocalize", false));
  EXPECT_TRUE(ros::service::exists("/localization/load_map", false));
}

TEST(VehicleNodelets, TheMapReachesTheMatcher) {
  // The map server serves around the initial pose (no TF yet) and the matcher holds chunks.
  std::string held;
  EXPECT_TRUE(waitFor(
      [&] {
        held = outputs->diagnosticValue("/localization/matcher: scan matching", "chunks held");
        return !held.empty() && std::stoi(held) >= 10;
      },
      60.0))
      << "chunks held by the matcher: '" << held << "'";
  EXPECT_EQ(outputs->diagnosticValue("/localization/map_server: vehicle position", "source")
                .find("initial"),
            0u)
      << "the map server did not serve around the initial pose";
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_nodelets_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  gmm_localization::node::outputs =
      std::make_unique<gmm_localization::node::vehicle_test::Outputs>(nh, false);
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  gmm_localization::node::outputs.reset();
  return result;
}
