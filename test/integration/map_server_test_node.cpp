// rostest node for the map_server nodelet (test/integration/map_server.test). It builds a small
// map with MapBuilder (one tile corrupted on purpose), loads gmm_localization/MapServerNodelet
// into the launch file's manager through its load_nodelet service, and checks:
//  - the index and the chunks: the set the planner expects around the configured initial
//    position, each chunk equal to an in-process rasterizeChunk of the map (bad tile absent);
//  - a diagnostic ERROR naming the corrupt tile, the rest served;
//  - a late subscriber receives every held chunk;
//  - load_map with a bad directory keeps serving; with a good one, a new map version;
//  - pose_hint and TF move the served area; map_cloud carries points with intensity and sigma;
//  - the nodelet unloads cleanly.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <set>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "gmm_localization/LoadMap.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "gmm_localization/ros/map_server_client.h"
#include "rostest_main.h"
#include "support/test_map.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr double kRadiusM = 8.0;
constexpr double kHysteresisM = 2.0;
const TileId kBadTile{3, 1};

/// A subscriber to map_chunks + map_index feeding a MapServerClient.
class ClientNode {
 public:
  explicit ClientNode(ros::NodeHandle& nh) {
    index_sub_ = nh.subscribe("/map_index", 10, &ClientNode::onIndex, this);
    chunk_sub_ = nh.subscribe("/map_chunks", 1000, &ClientNode::onChunk, this);
  }
  void onIndex(const MapIndex::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    client_.onIndex(m);
  }
  void onChunk(const RasterChunk::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++received_;
    std::string why;
    if (client_.onChunk(m, &why) == MapServerClient::ChunkVerdict::kInvalid) {
      ADD_FAILURE() << "invalid chunk: " << why;
    }
  }
  /// Waits until the client's chunks satisfy `served` (with its index complete and its map
  /// version != not_version).
  bool waitFor(const std::function<bool(const std::set<ChunkId>&)>& served, double timeout_s,
               uint64_t not_version = 0) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok() && ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (client_.hasIndex() && client_.complete() && served(heldLocked()) &&
            client_.mapVersion() != not_version) {
          return true;
        }
      }
      ros::WallDuration(0.02).sleep();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    ADD_FAILURE() << "client holds " << heldLocked().size()
                  << " chunks (index: " << client_.hasIndex()
                  << ", complete: " << client_.complete() << ", received " << received_ << ")";
    return false;
  }
  std::set<ChunkId> heldLocked() const {
    std::set<ChunkId> ids;
    for (const auto& kv : client_.chunks().chunks()) ids.insert(kv.first);
    return ids;
  }
  std::mutex mutex_;
  MapServerClient client_;
  size_t received_ = 0;

 private:
  ros::Subscriber index_sub_, chunk_sub_;
};

class MapServerRostest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testmap::tempDirectory("rostest");
    ASSERT_TRUE(testmap::build(dir_).ok());
    auto store = MapStore::open(dir_);
    ASSERT_TRUE(store.ok());
    const TileInfo* bad = store->tileInfo(kBadTile);
    ASSERT_NE(bad, nullptr);
    // The in-process reference map without the tile that is about to be corrupted.
    reference_ = GmmMap(store->geometry());
    for (const TileId& t : store->tileIds()) {
      if (t != kBadTile) reference_.insert(*store->loadTile(t));
    }
    planner_ = std::make_unique<ChunkPlanner>(store->geometry(), testmap::rasterOptions(),
                                              store->tileIds());
    ASSERT_TRUE(testmap::corruptFile(dir_ + "/" + bad->file_name));
    diag_sub_ = nh_.subscribe("/diagnostics", 100, &MapServerRostest::onDiagnostics, this);
  }
  void TearDown() override {
    diag_sub_.shutdown();  // before the members its callback writes (waits for one in progress)
    testmap::removeDirectory(dir_);
  }

  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(diag_mutex_);
    for (const auto& s : m->status) {
      if (s.name.find("map_server: map") != std::string::npos) map_status_ = s;
      if (s.name.find("map_server: vehicle position") != std::string::npos) position_status_ = s;
    }
  }

  void setParams(const std::string& ns) {
    const RasterOptions r = testmap::rasterOptions();
    ros::param::set(ns + "/map_directory", dir_);
    ros::param::set(ns + "/raster_radius_m", kRadiusM);
    ros::param::set(ns + "/tile_cache_radius_m", kRadiusM);
    ros::param::set(ns + "/hysteresis_m", kHysteresisM);
    ros::param::set(ns + "/update_period_s", 0.1);
    ros::param::set(ns + "/pose_hint_hold_s", 1.0);
    ros::param::set(ns + "/map_cloud_period_s", 0.1);
    ros::param::set(ns + "/chunk_shift", r.chunk_shift);
    ros::param::set(ns + "/num_layers", r.num_layers);
    ros::param::set(ns + "/z_step_m", r.z_step_m);
    ros::param::set(ns + "/z_coarsening_period", r.z_coarsening_period);
    ros::param::set(ns + "/worker_threads", 2);
    ros::param::set(ns + "/initial_position", std::vector<double>{10.0, 5.0});
  }

  bool loadNodelet(const std::string& name) {
    std::string manager;
    ros::param::param<std::string>("~manager", manager, "/test_manager");
    nodelet::NodeletLoad srv;
    srv.request.name = name;
    srv.request.type = "gmm_localization/MapServerNodelet";
    if (!ros::service::waitForService(manager + "/load_nodelet", ros::Duration(20.0))) {
      return false;
    }
    return ros::service::call(manager + "/load_nodelet", srv) && srv.response.success;
  }

  bool unloadNodelet(const std::string& name) {
    std::string manager;
    ros::param::param<std::string>("~manager", manager, "/test_manager");
    nodelet::NodeletUnload srv;
    srv.request.name = name;
    return ros::service::call(manager + "/unload_nodelet", srv) && srv.response.success;
  }

  /// The served set for a vehicle at `at`: every chunk planned within the radius, and nothing
  /// beyond radius + hysteresis.
  std::function<bool(const std::set<ChunkId>&)> servedAround(const PlanCentre& at) const {
    const auto ids = planner_->needed({at}, kRadiusM);
    const std::set<ChunkId> needed(ids.begin(), ids.end());
    return [this, at, needed](const std::set<ChunkId>& held) {
      for (const ChunkId& id : needed) {
        if (held.count(id) == 0) return false;
      }
      for (const ChunkId& id : held) {
        if (planner_->distanceToChunk(id, at) > kRadiusM + kHysteresisM) return false;
      }
      return true;
    };
  }

  void expectEqualToReference(ClientNode& c) {
    std::lock_guard<std::mutex> lock(c.mutex_);
    for (const auto& [id, got] : c.client_.chunks().chunks()) {
      auto want = rasterizeChunk(reference_, id, testmap::rasterOptions());
      ASSERT_TRUE(want.ok());
      ASSERT_TRUE(got->sameTables(**want)) << "chunk " << id.x << ", " << id.y;
      ASSERT_EQ(got->mixtures(), (*want)->mixtures());
    }
  }

  ros::NodeHandle nh_;
  std::string dir_;
  GmmMap reference_;
  std::unique_ptr<ChunkPlanner> planner_;
  ros::Subscriber diag_sub_;
  std::mutex diag_mutex_;
  diagnostic_msgs::DiagnosticStatus map_status_, position_status_;
};

TEST_F(MapServerRostest, ServesChunksSurvivesBadInputAndFollowsTheVehicle) {
  auto client = std::make_unique<ClientNode>(nh_);
  setParams("/map_server");
  ASSERT_TRUE(loadNodelet("/map_server")) << "the nodelet failed to load";

  // 1. The chunks around the initial position, equal to an in-process rasterization.
  const auto initial = servedAround(PlanCentre(10.0, 5.0));
  ASSERT_FALSE(planner_->needed({PlanCentre(10.0, 5.0)}, kRadiusM).empty());
  ASSERT_TRUE(client->waitFor(initial, 20.0));
  expectEqualToReference(*client);
  uint64_t version = 0;
  {
    std::lock_guard<std::mutex> lock(client->mutex_);
    const MapIndex& index = *client->client_.index();
    version = index.map_version;
    EXPECT_EQ(index.map_directory, dir_);
    EXPECT_EQ(index.header.frame_id, "map");
    EXPECT_DOUBLE_EQ(index.resolution_m, 0.2);
    EXPECT_EQ(index.tile_size_cells, 32);
    EXPECT_DOUBLE_EQ(index.origin_x_m, -5.0);
    EXPECT_EQ(index.chunk_shift, testmap::rasterOptions().chunk_shift);
    EXPECT_GT(index.raster_bytes, 0u);
    const MapSummary summary = MapStore::open(dir_)->summary();
    EXPECT_DOUBLE_EQ(index.min_x_m, summary.min_x_m);
    EXPECT_DOUBLE_EQ(index.max_x_m, summary.max_x_m);
    EXPECT_DOUBLE_EQ(index.min_y_m, summary.min_y_m);
    EXPECT_DOUBLE_EQ(index.max_y_m, summary.max_y_m);
    EXPECT_LT(index.min_x_m, index.max_x_m);
  }

  // 2. The corrupt tile: an ERROR diagnostic naming it; everything else was served above.
  const ros::WallTime diag_end = ros::WallTime::now() + ros::WallDuration(5.0);
  bool named = false;
  while (!named && ros::WallTime::now() < diag_end) {
    {
      std::lock_guard<std::mutex> lock(diag_mutex_);
      named = map_status_.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
              map_status_.message.find("(3, 1)") != std::string::npos;
    }
    ros::WallDuration(0.05).sleep();
  }
  EXPECT_TRUE(named) << "map diagnostic: " << map_status_.message;

  // 3. A late subscriber receives every held chunk. ROS shares one connection per process and
  // topic, so the first client unsubscribes before the late one connects.
  client.reset();
  client = std::make_unique<ClientNode>(nh_);
  EXPECT_TRUE(client->waitFor(initial, 10.0));
  expectEqualToReference(*client);

  // 4. load_map with a bad directory keeps the map (a new client still gets all of it).
  LoadMap bad;
  bad.request.map_directory = "/nonexistent/gmm_map";
  ASSERT_TRUE(ros::service::call("/load_map", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("/nonexistent/gmm_map"), std::string::npos)
      << bad.response.message;
  client.reset();
  client = std::make_unique<ClientNode>(nh_);
  EXPECT_TRUE(client->waitFor(initial, 10.0));
  {
    std::lock_guard<std::mutex> lock(client->mutex_);
    EXPECT_EQ(client->client_.mapVersion(), version);
  }

  // 5. pose_hint moves the served area (no TF yet: the hint replaces the initial position).
  ros::Publisher hint_pub =
      nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("/pose_hint", 1, true);
  geometry_msgs::PoseWithCovarianceStamped hint;
  hint.header.frame_id = "map";
  hint.header.stamp = ros::Time::now();
  hint.pose.pose.position.x = 22.0;
  hint.pose.pose.position.y = 5.0;
  hint.pose.pose.orientation.w = 1.0;
  hint_pub.publish(hint);
  ASSERT_TRUE(client->waitFor(servedAround(PlanCentre(22.0, 5.0)), 20.0));

  // 6. TF map -> base_link wins once the hint is older than pose_hint_hold_s.
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "map";
  t.child_frame_id = "base_link";
  t.transform.translation.x = 0.0;
  t.transform.translation.y = 5.0;
  t.transform.rotation.w = 1.0;
  tf.sendTransform(t);
  ASSERT_TRUE(client->waitFor(servedAround(PlanCentre(0.0, 5.0)), 20.0));
  expectEqualToReference(*client);

  // 7. map_cloud: latched, points with intensity (= components) and sigma fields.
  sensor_msgs::PointCloud2::ConstPtr cloud;
  for (int attempt = 0; attempt < 50 && !cloud; ++attempt) {
    cloud =
        ros::topic::waitForMessage<sensor_msgs::PointCloud2>("/map_cloud", nh_, ros::Duration(0.5));
    if (cloud && cloud->width == 0) cloud.reset();  // built before the chunks came
  }
  ASSERT_TRUE(cloud);
  EXPECT_EQ(cloud->header.frame_id, "map");
  std::set<std::string> fields;
  for (const auto& f : cloud->fields) fields.insert(f.name);
  EXPECT_EQ(fields, std::set<std::string>({"x", "y", "z", "intensity", "sigma"}));

  // 8. load_map with a good map: a new version, chunks served again.
  const std::string other = testmap::tempDirectory("rostest_other");
  ASSERT_TRUE(testmap::build(other).ok());
  LoadMap good;
  good.request.map_directory = other;
  ASSERT_TRUE(ros::service::call("/load_map", good));
  EXPECT_TRUE(good.response.success) << good.response.message;
  EXPECT_TRUE(client->waitFor(servedAround(PlanCentre(0.0, 5.0)), 20.0, version));
  {
    std::lock_guard<std::mutex> lock(client->mutex_);
    EXPECT_EQ(client->client_.mapVersion(), version + 1);
    EXPECT_EQ(client->client_.index()->map_directory, other);
  }

  EXPECT_TRUE(unloadNodelet("/map_server"));
  testmap::removeDirectory(other);
}

TEST_F(MapServerRostest, MissingMapDirectoryFailsToLoad) {
  ros::param::set("/broken_server/map_directory", "/nonexistent/gmm_map");
  EXPECT_FALSE(loadNodelet("/broken_server"));
  ros::param::del("/broken_server/map_directory");
  EXPECT_FALSE(loadNodelet("/broken_server2"));  // no map_directory at all
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  return gmm_localization::node::runRostestMain(argc, argv, "map_server_rostest");
}
