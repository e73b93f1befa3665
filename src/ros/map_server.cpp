#include "gmm_localization/ros/map_server.h"

#include <sensor_msgs/PointCloud2.h>

#include "gmm_localization/ros/map_server_load.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr uint32_t kChunkQueueSize = 256;  // a full radius of chunks fits in one burst

}  // namespace

MapServer::MapServer(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : nh_(nh),
      pnh_(pnh),
      name_(name),
      options_(loadNodeletOptions(pnh, name, loadMapServerOptions)) {
  // Publishers first: the engine publishes from its workers as soon as it has a position.
  ros::AdvertiseOptions chunk_ops = ros::AdvertiseOptions::create<RasterChunk>(
      "map_chunks", kChunkQueueSize,
      [this](const ros::SingleSubscriberPublisher& pub) { onChunkSubscriber(pub); },
      ros::SubscriberStatusCallback(), ros::VoidConstPtr(), &connect_queue_);
  chunk_pub_ = nh_.advertise(chunk_ops);
  index_pub_ = nh_.advertise<MapIndex>("map_index", 1, /*latch=*/true);
  cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("map_cloud", 1, /*latch=*/true);
  ChunkEngine::Callbacks callbacks;
  callbacks.on_chunk = [this](const MapChunkConstPtr& c, uint64_t v) { return publishChunk(c, v); };
  callbacks.on_held_changed = [this]() { onHeldChanged(); };
  callbacks.on_tile_error = [this](const TileId& t, const std::string& why) {
    onTileError(t, why);
  };
  callbacks.on_tile_recovered = [this](const TileId& t) {
    ROS_INFO("%s: tile (%d, %d) loads again: the chunks served without it are rasterized again",
             name_.c_str(), t.x, t.y);
  };
  const auto first_version = static_cast<uint64_t>(ros::WallTime::now().toNSec() / 1000000);
  auto engine =
      ChunkEngine::create(options_.map_directory, options_.engine, callbacks, first_version);
  if (!engine) {
    throw ConfigError("cannot serve map_directory: " + engine.error() +
                      layerHint(options_.map_directory, options_.layer));
  }
  const std::string layer = layerProblem(*(*engine)->store(), options_.layer);
  if (!layer.empty()) throw ConfigError("cannot serve map_directory: " + layer);
  engine_ = std::move(*engine);
  publishIndex();

  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  pose_hint_sub_ = nh_.subscribe("pose_hint", 1, &MapServer::onPoseHint, this);
  region_hint_sub_ = nh_.subscribe("region_hint", 1, &MapServer::onPoseHint, this);
  load_map_srv_ = nh_.advertiseService("load_map", &MapServer::onLoadMap, this);
  setUpDiagnostics();
  update_timer_ = nh_.createWallTimer(ros::WallDuration(options_.update_period_s),
                                      [this](const ros::WallTimerEvent&) { onUpdate(); });
  // Last: nothing may throw once this thread runs (connect callbacks wait in their queue).
  connect_thread_ = std::thread([this]() {
    while (!stopping_ && nh_.ok()) connect_queue_.callAvailable(ros::WallDuration(0.1));
  });
  const MapSummary s = engine_->mapSummary();
  ROS_INFO(
      "%s: serving map '%s' (%zu tiles, x [%.1f, %.1f] m, y [%.1f, %.1f] m), chunks of %d "
      "cells within %.0f m of %s, %d worker thread(s)",
      name_.c_str(), options_.map_directory.c_str(), s.tiles, s.min_x_m, s.max_x_m, s.min_y_m,
      s.max_y_m, options_.engine.raster.chunkCells(), options_.engine.raster_radius_m,
      options_.base_frame.c_str(), options_.engine.worker_threads);
  onUpdate();
}

MapServer::~MapServer() {
  // Inputs first (nothing may reach the engine once it is gone), then the engine's workers,
  // then the connect thread; the publishers they use go last, with the members.
  update_timer_.stop();
  pose_hint_sub_.shutdown();
  region_hint_sub_.shutdown();
  load_map_srv_.shutdown();
  diagnostics_.reset();
  engine_.reset();
  stopping_ = true;
  if (connect_thread_.joinable()) connect_thread_.join();
  chunk_pub_.shutdown();  // removes its connect callbacks from connect_queue_ while it exists
}

void MapServer::onUpdate() {
  const CentreSelection where = locateVehicle();
  engine_->setCentres(where.centres);
  if (cloud_pub_.getNumSubscribers() > 0) publishMapCloud(where.centres);
  resendIndexIfQuiet();
}

bool MapServer::onLoadMap(LoadMap::Request& req, LoadMap::Response& res) {
  // Every tile of the new map is checked first: a truncated or CRC-broken one refuses the map.
  const LoadMapOutcome outcome = loadMapDirectory(*engine_, req.map_directory, 5, options_.layer);
  res.success = outcome.success;
  res.message = outcome.message;
  if (!outcome.success) {
    ROS_ERROR("%s: load_map failed: %s", name_.c_str(), res.message.c_str());
    return true;
  }
  ROS_INFO("%s: %s", name_.c_str(), res.message.c_str());
  {
    std::lock_guard<std::mutex> lock(msgs_mutex_);
    cloud_dirty_ = true;
  }
  onUpdate();
  return true;
}

}  // namespace node
}  // namespace gmm_localization
