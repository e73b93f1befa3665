#pragma once
// The map server: serves the rasterized multiresolution map (paper IV-B) around the vehicle.
// A thin ROS shell around ChunkEngine (core/raster/chunk_engine.h), which loads the
// parametric tiles near the vehicle and rasterizes chunks on background threads.
//
// Topics (relative; remap in launch):
//   map_chunks  gmm_localization/RasterChunk, published as ConstPtr (zero copy to subscribers in
//               the same nodelet manager), queue 256, nearest chunks first. A subscriber that
//               connects later is sent every chunk held at that moment (to it alone). ROS keeps
//               one connection per process and topic: a second subscription in a process that
//               already subscribes shares it and gets no re-send (subscribe once per process,
//               e.g. through one MapServerClient).
//   map_index   gmm_localization/MapIndex, latched, republished on every change: map version,
//               geometry, raster options, the chunks held, their memory, the map's extent;
//               re-sent unchanged (same stamp) every index_period_s otherwise, so subscribers
//               know the server is alive (map_server_client.h: one map server at a time).
//   map_cloud   sensor_msgs/PointCloud2 in map_frame, latched, built only while subscribed and
//               rebuilt (at most every map_cloud_period_s) when the chunks change: one point per
//               non-empty cell within map_cloud_radius_m (map_server_cloud.h); fields x y z
//               intensity (= number of components) sigma.
//   pose_hint   (subscribed) geometry_msgs/PoseWithCovarianceStamped in map_frame, e.g. rviz's
//               /initialpose: where to serve chunks while TF cannot say.
//   region_hint (subscribed) the same from the global start (global_start.h): the window it is
//               about to search, served before its pose goes out on /initialpose.
// Service:
//   load_map    gmm_localization/LoadMap: switch to another map directory (or reload this
//               one). Every tile is read first (map_server_load.h): a directory whose tiles are
//               missing, truncated or CRC-broken is refused, `message` naming the tiles and the
//               reasons, and the current map stays. On success: a new map_version, chunks
//               dropped and re-served.
// Subscribers follow the protocol of map_server_client.h (stamps from one increasing clock;
// the index is the authority on what is held). map_version starts at the wall-clock time of
// start-up in milliseconds, so that a restarted server never repeats a version.
//
// Vehicle position: TF map_frame -> base_frame (latest), else pose_hint, else the configured
// initial position (core/raster/chunk_planner.h, selectCentres), polled every update_period_s.
// Tiles that fail to load are served as empty and retried every tile_retry_period_s
// (chunk_engine.h): a restored directory heals without a reload.
// Diagnostics (/diagnostics): map (version, tiles, extent, tile load errors: ERROR naming the
// tiles), chunks (held, pending, memory, rasterization times), vehicle position (source;
// WARN when unknown or outside the map's extent).
// Threads: rasterization and chunk publication run on the engine's workers; connect callbacks
// on their own thread; nothing rasterizes in a ROS callback.

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "gmm_localization/LoadMap.h"
#include "gmm_localization/MapIndex.h"
#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/raster/chunk_engine.h"
#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/map_server_options.h"

namespace gmm_localization {
namespace node {

class MapServer {
 public:
  /// Loads the options and the map and starts serving. Throws ConfigError with the reason on a
  /// bad parameter or an unreadable map.
  MapServer(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~MapServer();
  MapServer(const MapServer&) = delete;
  MapServer& operator=(const MapServer&) = delete;

 private:
  // map_server.cpp: set-up, the update timer, the service.
  void onUpdate();
  bool onLoadMap(LoadMap::Request& req, LoadMap::Response& res);
  // map_server_position.cpp: where the vehicle is.
  void onPoseHint(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  CentreSelection locateVehicle();
  // map_server_publish.cpp: chunks, index, map cloud.
  MapChunkConstPtr publishChunk(const MapChunkConstPtr& chunk, uint64_t map_version);
  void onHeldChanged();
  void onTileError(const TileId& tile, const std::string& reason);
  void publishIndex();
  /// Re-sends the last index when none went out for index_period_s (a heartbeat).
  void resendIndexIfQuiet();
  void onChunkSubscriber(const ros::SingleSubscriberPublisher& pub);
  void publishMapCloud(const std::vector<PlanCentre>& centres);
  ros::Time nextStamp();
  // map_server_diagnostics.cpp
  void setUpDiagnostics();

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  MapServerOptions options_;

  // Connect callbacks of map_chunks run on their own queue and thread: re-sending every held
  // chunk to a late subscriber may take a while and must not hold up the nodelet's callbacks.
  // Declared before the publisher, whose destruction removes its callbacks from this queue.
  ros::CallbackQueue connect_queue_;
  std::thread connect_thread_;
  std::atomic<bool> stopping_{false};

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Subscriber pose_hint_sub_, region_hint_sub_;
  ros::Publisher chunk_pub_, index_pub_, cloud_pub_;
  ros::ServiceServer load_map_srv_;
  ros::WallTimer update_timer_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex stamp_mutex_;
  ros::Time last_stamp_;

  std::mutex msgs_mutex_;  // published messages of the held chunks (for late subscribers)
  std::map<ChunkId, RasterChunk::ConstPtr> msgs_;
  bool cloud_dirty_ = true;
  std::vector<PlanCentre> cloud_centres_;  // where the last map cloud was built
  ros::WallTime last_cloud_time_;

  std::mutex position_mutex_;  // guards the position state below
  std::optional<PlanCentre> last_tf_, hint_;
  ros::WallTime last_tf_time_, hint_time_;
  CentreSelection centres_;
  std::string tf_error_;

  std::mutex index_mutex_;  // serialises index publications; guards the two below
  MapIndex::ConstPtr last_index_;
  ros::WallTime last_index_time_;

  std::unique_ptr<ChunkEngine> engine_;  // last member: destroyed first, stopping the workers
};

}  // namespace node
}  // namespace gmm_localization
