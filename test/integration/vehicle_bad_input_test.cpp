// rostest of launch/localization.launch against bad input (vehicle_bad_input.test): this node
// plays the fixture's 20 s drive on sim time (vehicle_test_player.h) and, between the drive's
// own messages, sends one bad input after another - the bad-input matrix of docs/ros.md:
//   clouds: a missing field, truncated data, empty, all NaN, some points Inf, points at 1e30 m
//           and 2e5 m, 1.5 million points, a frame TF does not know, stamps 1e5 s ahead and
//           1e4 s behind the clock;
//   NaN IMU, NaN INS odometry, a NaN /initialpose;
//   a rogue map index (another publisher, version 2^63, resolution 0);
//   the map: load_map of a directory that was removed, of one with a truncated and a corrupted
//   tile, then of the restored directory.
// For each: the stack stays up, a status or a diagnostic names the cause, nothing non-finite is
// published, and matching goes on with good input (accepted matches right after). The drive
// ends localized. The tests run in order on one running system.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "bad_clouds.h"
#include "gmm_localization/LoadMap.h"
#include "gmm_localization/MapIndex.h"
#include "vehicle_test_player.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code
namespace fs = std::filesystem;

const char* kEkfFilter = "/localization/ekf: filter";
const char* kMatcherDiag = "/localization/matcher: scan matching";

std::unique_ptr<Outputs> outputs;
std::unique_ptr<FaultyPlayer> player;
ros::Publisher scan_pub, imu_pub, odom_pub, initialpose_pub, index_pub;
fs::path work_dir;             ///< this test's copies of the fixture map
std::set<ros::Time> injected;  ///< stamps of the scans this node sent

double wallNow() { return ros::WallTime::now().toSec(); }
double rel(const ros::Time& stamp) { return (stamp - player->start()).toSec(); }

void reach(double rel_s) {
  ASSERT_TRUE(waitFor([&] { return player->elapsed() >= rel_s || player->finished(); }, 120.0))
      << "the player never reached " << rel_s << " s";
}

/// A copy of the drive's last scan stamped 0.1 ms after it: what the vehicle saw there, and a
/// stamp between the drive's scans.
sensor_msgs::PointCloud2 freshScan() {
  const sensor_msgs::PointCloud2ConstPtr last = player->lastScan();
  EXPECT_TRUE(last) << "no scan published yet";
  sensor_msgs::PointCloud2 msg = last ? *last : sensor_msgs::PointCloud2();
  msg.header.stamp += ros::Duration(1e-4);
  return msg;
}

/// Sends a scan of this node's (its stamp remembered, so that the drive's scans are told apart).
void sendScan(const sensor_msgs::PointCloud2& msg) {
  outputs->locked([&] { return injected.insert(msg.header.stamp); });
  scan_pub.publish(msg);
}

template <typename Pred>
size_t countStatuses(double from_rel, double to_rel, Pred pred) {
  return outputs->locked([&] {
    size_t n = 0;
    for (const MatchStatus& s : outputs->statuses_) {
      const double r = rel(s.header.stamp);
      if (r >= from_rel && r < to_rel && pred(s)) ++n;
    }
    return n;
  });
}

size_t acceptedIn(double from_rel, double to_rel) {
  return countStatuses(from_rel, to_rel, [](const MatchStatus& s) { return s.accepted; });
}

std::string describeStatuses(double from_rel, double to_rel) {
  return outputs->locked([&] {
    std::string all;
    for (const MatchStatus& s : outputs->statuses_) {
      const double r = rel(s.header.stamp);
      if (r < from_rel || r >= to_rel) continue;
      char line[64];
      std::snprintf(line, sizeof(line), "\n  %.3f s ", r);
      all += line + (s.accepted ? std::string("accepted") : s.reason);
    }
    return all;
  });
}

/// The status of the scan stamped `stamp` (waits for it).
std::optional<MatchStatus> statusOf(const ros::Time& stamp, double timeout_s) {
  std::optional<MatchStatus> found;
  waitFor(
      [&] {
        return outputs->locked([&] {
          for (const MatchStatus& s : outputs->statuses_) {
            if (s.header.stamp == stamp) found = s;
          }
          return found.has_value();
        });
      },
      timeout_s);
  return found;
}

/// Matching goes on with good input: of the drive's first `scans` scans stamped after `after`,
/// at least `accepted` are accepted.
void expectMatchingGoesOn(const std::string& what, const ros::Time& after, size_t scans = 3,
                          size_t at_least = 2) {
  std::vector<MatchStatus> next;
  waitFor(
      [&] {
        next = outputs->locked([&] {
          std::vector<MatchStatus> found;
          for (const MatchStatus& s : outputs->statuses_) {
            if (s.header.stamp > after && injected.count(s.header.stamp) == 0) found.push_back(s);
          }
          std::sort(found.begin(), found.end(), [](const MatchStatus& a, const MatchStatus& b) {
            return a.header.stamp < b.header.stamp;
          });
          found.resize(std::min(found.size(), scans));
          return found;
        });
        return next.size() >= scans || player->finished();
      },
      20.0);
  ASSERT_EQ(next.size(), scans) << "after " << what << ": fewer scans answered (the drive ended)";
  const size_t accepted =
      std::count_if(next.begin(), next.end(), [](const MatchStatus& s) { return s.accepted; });
  EXPECT_GE(accepted, at_least) << "after " << what << ": " << describeStatuses(rel(after), 1e9);
}

/// The drive's position as a stamp (what a node sending now would stamp).
ros::Time clockNow() { return player->start() + ros::Duration(player->elapsed()); }

/// A numeric diagnostic value (the latest), -1 when absent.
long diagnosticCount(const char* name, const char* key) {
  const std::string v = outputs->diagnosticValue(name, key);
  return v.empty() ? -1 : std::stol(v);
}

/// Waits (diagnostics come at 1 Hz) until the value reaches at least `at_least`; returns it.
long waitForCount(const char* name, const char* key, long at_least) {
  long v = -1;
  waitFor([&] { return (v = diagnosticCount(name, key)) >= at_least; }, 5.0);
  return v;
}

TEST(VehicleBadInput, StartsOnACopyOfTheMap) {
  std::string map;
  ASSERT_TRUE(ros::param::get("~map", map));
  work_dir = fs::temp_directory_path() / ("gmm_bad_input_" + std::to_string(::getpid()));
  fs::remove_all(work_dir);
  fs::create_directories(work_dir);
  fs::copy(map, work_dir / "map", fs::copy_options::recursive);
  ASSERT_TRUE(ros::service::waitForService("/localization/load_map", ros::Duration(30.0)));
  LoadMap load;
  load.request.map_directory = (work_dir / "map").string();
  ASSERT_TRUE(ros::service::call("/localization/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;

  ASSERT_TRUE(waitFor([] { return initialpose_pub.getNumSubscribers() > 0; }, 30.0));
  player->publishStartClock();
  ros::WallDuration(0.5).sleep();
  auto t = player->truth().at(player->start().toSec());
  ASSERT_TRUE(t.has_value());
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.frame_id = "map";
  pose.header.stamp = player->start();
  Pose6 p = *t;
  p.x += 1.0;
  p.z = p.roll = p.pitch = 0.0;
  pose.pose.pose = toMsg(p);
  pose.pose.covariance[0] = pose.pose.covariance[7] = 0.25;
  pose.pose.covariance[35] = 0.0076;
  const double since = wallNow();
  initialpose_pub.publish(pose);
  // The map server rasterizes around the pose hint before the drive starts.
  ASSERT_TRUE(outputs->mapReadySince(since, 60.0)) << "no map around /initialpose";
  ros::WallDuration(0.5).sleep();  // the chunks' way to the matcher
  player->play();
  reach(3.0);
  EXPECT_GE(acceptedIn(0.0, 3.0), 5u) << describeStatuses(0.0, 3.0);
}

TEST(VehicleBadInput, BadCloudsAreAnsweredWithTheirCause) {
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<CloudCase> cases = unmatchableClouds();
  const std::vector<CloudCase> matchable = {
      {"every 7th point Inf", [inf](sensor_msgs::PointCloud2& m) { setPoints(m, inf, 7); },
       nullptr},
      {"every 50th point at 1e30 m", [](sensor_msgs::PointCloud2& m) { setPoints(m, 1e30f, 50); },
       nullptr},
      {"every 50th point at 2e5 m", [](sensor_msgs::PointCloud2& m) { setPoints(m, 2e5f, 50); },
       nullptr},
      {"1.5 million points",
       [](sensor_msgs::PointCloud2& m) {
         const size_t copies = 1500000 / m.width + 1;
         std::vector<uint8_t> data;
         data.reserve(m.data.size() * copies);
         for (size_t c = 0; c < copies; ++c) data.insert(data.end(), m.data.begin(), m.data.end());
         m.data.swap(data);
         m.width *= copies;
         m.row_step = m.width * m.point_step;
       },
       nullptr},
      {"unknown frame", [](sensor_msgs::PointCloud2& m) { m.header.frame_id = "nowhere_frame"; },
       "no transform from the cloud frame"},
  };
  cases.insert(cases.end(), matchable.begin(), matchable.end());
  for (const CloudCase& c : cases) {
    sensor_msgs::PointCloud2 msg = freshScan();
    c.spoil(msg);
    const double sent = wallNow();
    sendScan(msg);
    const auto s = statusOf(msg.header.stamp, 20.0);
    ASSERT_TRUE(s) << c.what << ": no status for the scan";
    std::printf("[vehicle_bad_input] %-28s -> %s (%.2f s)\n", c.what,
                s->accepted ? "accepted" : s->reason.c_str(), wallNow() - sent);
    if (c.reason) {
      EXPECT_FALSE(s->accepted) << c.what;
      EXPECT_NE(s->reason.find(c.reason), std::string::npos) << c.what << ": " << s->reason;
    } else {
      EXPECT_TRUE(s->accepted || !s->reason.empty()) << c.what;
    }
    expectMatchingGoesOn(c.what, msg.header.stamp);
  }
  EXPECT_GE(waitForCount(kMatcherDiag, "malformed or empty clouds", 3), 3)
      << "matcher diagnostic 'malformed or empty clouds'";
}

TEST(VehicleBadInput, StampsFarAheadAndFarBehindAreRefusedNotFollowed) {
  for (const double offset : {1e5, -1e4}) {
    sensor_msgs::PointCloud2 msg = freshScan();
    const ros::Time good_stamp = msg.header.stamp;
    msg.header.stamp += ros::Duration(offset);
    sendScan(msg);
    const auto s = statusOf(msg.header.stamp, 20.0);
    ASSERT_TRUE(s) << "no status for a scan stamped " << offset << " s off the clock";
    std::printf("[vehicle_bad_input] scan stamped %+.0f s       -> %s\n", offset,
                s->accepted ? "accepted" : s->reason.c_str());
    EXPECT_FALSE(s->accepted) << offset;
    EXPECT_NE(s->reason.find(offset > 0 ? "after the clock" : "before the clock"),
              std::string::npos)
        << s->reason;
    expectMatchingGoesOn("a scan stamped " + std::to_string(offset) + " s off the clock",
                         good_stamp);
  }
  // Neither stamp reset the session, nor made the next good scan look like time going back.
  EXPECT_EQ(outputs->diagnosticValue(kMatcherDiag, "time went backwards (resets)"), "0");
}

TEST(VehicleBadInput, NanImuOdometryAndInitialPoseAreDroppedWithAReason) {
  const long before = diagnosticCount(kEkfFilter, "invalid inputs");
  ASSERT_GE(before, 0) << "no 'invalid inputs' in the EKF's filter diagnostic";
  const double wall = wallNow();
  const double nan = std::nan("");
  for (int i = 0; i < 3; ++i) {
    reach(player->elapsed() + 0.1);
    sensor_msgs::Imu imu;
    imu.header.stamp = clockNow();
    imu.header.frame_id = "base_link";
    imu.orientation.w = nan;
    imu.angular_velocity.z = nan;
    imu.linear_acceleration.x = nan;
    imu_pub.publish(imu);
    nav_msgs::Odometry odom;
    odom.header.stamp = imu.header.stamp + ros::Duration(0.001);
    odom.header.frame_id = "odom";
    odom.child_frame_id = "base_link";
    odom.pose.pose.position.x = nan;
    odom.pose.pose.orientation.w = 1.0;
    odom.twist.twist.linear.x = nan;
    odom_pub.publish(odom);
  }
  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.frame_id = "map";
  pose.header.stamp = clockNow();
  pose.pose.pose.position.x = nan;
  pose.pose.pose.orientation.w = 1.0;
  initialpose_pub.publish(pose);
  expectMatchingGoesOn("NaN IMU, odometry and initial pose", clockNow());
  EXPECT_GE(waitForCount(kEkfFilter, "invalid inputs", before + 7), before + 7)
      << "the EKF's 'invalid inputs' did not count the NaN IMU, odometry and initial pose";
  EXPECT_TRUE(outputs->sawLog(rosgraph_msgs::Log::WARN, "initial pose", wall))
      << "no log line for the NaN initial pose";
}

TEST(VehicleBadInput, ARogueMapIndexIsIgnored) {
  const long before =
      diagnosticCount(kMatcherDiag, "map indices ignored (other publishers, invalid)");
  MapIndex index;
  index.header.stamp = clockNow();
  index.header.frame_id = "map";
  index.map_directory = "rogue";
  index.map_version = uint64_t{1} << 63;
  index.resolution_m = 0.0;
  index.tile_size_cells = 64;
  index.num_layers = 3;
  index.chunk_shift = 6;
  for (int i = 0; i < 3; ++i) {
    index_pub.publish(index);
    ros::WallDuration(0.2).sleep();
  }
  expectMatchingGoesOn("a rogue map index", clockNow());
  EXPECT_GT(
      waitForCount(kMatcherDiag, "map indices ignored (other publishers, invalid)", before + 1),
      before);
  // Still the map server's (its manager's caller id), not this node's.
  const std::string followed = outputs->diagnosticValue(kMatcherDiag, "map server followed");
  EXPECT_FALSE(followed.empty());
  EXPECT_EQ(followed.find(ros::this_node::getName()), std::string::npos) << followed;
}

/// load_map of `dir` (wall time of the answer recorded); returns the response.
LoadMap::Response loadMap(const fs::path& dir) {
  LoadMap load;
  load.request.map_directory = dir.string();
  EXPECT_TRUE(ros::service::call("/localization/load_map", load));
  return load.response;
}

TEST(VehicleBadInput, ABrokenMapDirectoryKeepsTheServedMap) {
  const fs::path live = work_dir / "map", aside = work_dir / "map_aside";
  // Removed: load_map refuses it, the served map stays.
  fs::rename(live, aside);
  const LoadMap::Response removed = loadMap(live);
  EXPECT_FALSE(removed.success);
  EXPECT_NE(removed.message.find(live.string()), std::string::npos) << removed.message;
  std::printf("[vehicle_bad_input] load_map removed dir      -> %s\n", removed.message.c_str());
  expectMatchingGoesOn("load_map of a removed directory", clockNow());
  // A truncated and a corrupted tile: refused, naming the tile.
  const fs::path broken = work_dir / "broken";
  fs::copy(aside, broken, fs::copy_options::recursive);
  std::vector<fs::path> tiles;
  for (const auto& e : fs::directory_iterator(broken)) {
    if (e.path().extension() == ".gmt") tiles.push_back(e.path());
  }
  std::sort(tiles.begin(), tiles.end());
  ASSERT_GE(tiles.size(), 2u);
  fs::resize_file(tiles[0], fs::file_size(tiles[0]) / 2);
  {
    std::fstream f(tiles[1], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(tiles[1]) / 2));
    f.put('\x5a').put('\xa5').put('\x5a');
  }
  const LoadMap::Response bad = loadMap(broken);
  std::printf("[vehicle_bad_input] load_map broken tiles     -> %s\n", bad.message.c_str());
  EXPECT_FALSE(bad.success);
  EXPECT_NE(bad.message.find(tiles[0].filename().string()), std::string::npos) << bad.message;
  expectMatchingGoesOn("load_map of a directory with broken tiles", clockNow());
  // Restored: load_map takes it again.
  fs::rename(aside, live);
  const LoadMap::Response restored = loadMap(live);
  EXPECT_TRUE(restored.success) << restored.message;
  // A new map version: the matcher waits for its chunks ("no map") for a few scans.
  expectMatchingGoesOn("load_map of the restored directory", clockNow(), 10, 3);
}

TEST(VehicleBadInput, EndsLocalizedAndNothingNonFiniteWasPublished) {
  ASSERT_TRUE(waitFor([] { return player->finished(); }, 120.0));
  ros::WallDuration(2.0).sleep();
  expectEndsLocalized(*outputs, player->truth(), "vehicle_bad_input", kTolXyM, kTolYawRad);
  expectNothingNonFinite(*outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_bad_input_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  using namespace gmm_localization::node;  // NOLINT: test code
  std::string bag;
  if (!ros::param::get("~bag", bag)) {
    std::fprintf(stderr, "missing ~bag (fixture.yaml)\n");
    return 1;
  }
  outputs = std::make_unique<vehicle_test::Outputs>(nh, /*subscribe_truth=*/false);
  player = std::make_unique<vehicle_test::FaultyPlayer>(nh, bag, vehicle_test::Faults());
  scan_pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 2);
  imu_pub = nh.advertise<sensor_msgs::Imu>("/imu/data", 200);
  odom_pub = nh.advertise<nav_msgs::Odometry>("/ins/odom", 100);
  initialpose_pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1);
  index_pub = nh.advertise<gmm_localization::MapIndex>("/localization/map_index", 1);
  const int result = RUN_ALL_TESTS();
  player.reset();
  spinner.stop();
  outputs.reset();
  std::error_code ignored;
  std::filesystem::remove_all(work_dir, ignored);
  return result;
}
