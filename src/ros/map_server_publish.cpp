// Publication: raster chunks, the map index, re-sending to late subscribers, the map cloud.
#include <set>

#include <sensor_msgs/PointCloud2.h>
#include <boost/make_shared.hpp>

#include "gmm_localization/ros/chunk_conversion.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/map_server.h"
#include "gmm_localization/ros/map_server_client.h"
#include "gmm_localization/ros/map_server_cloud.h"

namespace gmm_localization {
namespace node {

ros::Time MapServer::nextStamp() {
  // One strictly increasing clock for chunks and indices (map_server_client.h): even with sim
  // time paused, at zero before /clock, or jumping back, a later publication has a later stamp.
  std::lock_guard<std::mutex> lock(stamp_mutex_);
  ros::Time now = ros::Time::now();
  if (now <= last_stamp_) now = last_stamp_ + ros::Duration(0, 1);
  last_stamp_ = now;
  return now;
}

MapChunkConstPtr MapServer::publishChunk(const MapChunkConstPtr& chunk, uint64_t map_version) {
  // Runs on an engine worker. The held chunk shares the published message's memory (fromMsg),
  // so the tables exist once: in the message that subscribers of this manager also share.
  auto msg = boost::make_shared<RasterChunk>();
  toMsg(*chunk, map_version, options_.map_frame, nextStamp(), *msg);
  RasterChunk::ConstPtr cmsg = msg;
  auto shared = fromMsg(cmsg);
  if (!shared) {  // cannot happen for a chunk toMsg wrote; keep the original then
    ROS_ERROR_THROTTLE(10.0, "%s: chunk message does not read back: %s", name_.c_str(),
                       shared.error().c_str());
    return chunk;
  }
  {
    std::lock_guard<std::mutex> lock(msgs_mutex_);
    msgs_[chunk->id()] = cmsg;
    cloud_dirty_ = true;
  }
  chunk_pub_.publish(cmsg);
  return *shared;
}

void MapServer::onHeldChanged() {
  // Called by the engine (serialised with publishChunk) after every addition and eviction.
  std::set<ChunkId> held;
  for (const MapChunkConstPtr& c : engine_->held()) held.insert(c->id());
  {
    std::lock_guard<std::mutex> lock(msgs_mutex_);
    for (auto it = msgs_.begin(); it != msgs_.end();) {
      if (held.count(it->first) == 0) {
        it = msgs_.erase(it);
        cloud_dirty_ = true;
      } else {
        ++it;
      }
    }
  }
  publishIndex();
}

void MapServer::onTileError(const TileId& tile, const std::string& reason) {
  ROS_ERROR_THROTTLE(
      5.0, "%s: skipping tile (%d, %d) (served as empty, tried again every %g s): %s",
      name_.c_str(), tile.x, tile.y, options_.engine.tile_retry_period_s, reason.c_str());
}

void MapServer::publishIndex() {
  std::lock_guard<std::mutex> publish(index_mutex_);
  auto index = boost::make_shared<MapIndex>();
  const auto store = engine_->store();
  const MapSummary summary = engine_->mapSummary();
  const std::vector<MapChunkConstPtr> held = engine_->held();
  index->header.frame_id = options_.map_frame;
  index->map_directory = store->directory();
  index->map_version = engine_->mapVersion();
  toMsg(store->geometry(), options_.engine.raster, *index);
  toMsg(store->manifest().georeference, *index);
  for (const MapChunkConstPtr& c : held) {
    index->chunk_x.push_back(c->id().x);
    index->chunk_y.push_back(c->id().y);
    index->raster_bytes += c->bytes();
  }
  index->min_x_m = summary.min_x_m;
  index->min_y_m = summary.min_y_m;
  index->max_x_m = summary.max_x_m;
  index->max_y_m = summary.max_y_m;
  index->header.stamp = nextStamp();
  last_index_ = index;
  last_index_time_ = ros::WallTime::now();
  index_pub_.publish(last_index_);
}

void MapServer::resendIndexIfQuiet() {
  std::lock_guard<std::mutex> publish(index_mutex_);
  const ros::WallTime now = ros::WallTime::now();
  if (!last_index_ || (now - last_index_time_).toSec() < options_.index_period_s) return;
  // The same message, stamp included: a chunk published since has a later stamp than it, so
  // the re-send can never look like an eviction to a subscriber (map_server_client.h).
  last_index_time_ = now;
  index_pub_.publish(last_index_);
}

void MapServer::onChunkSubscriber(const ros::SingleSubscriberPublisher& pub) {
  // On the connect thread. The latched index reaches the new subscriber by itself; the chunks
  // held now are sent to it alone (serialised: a SingleSubscriberPublisher cannot share).
  std::vector<RasterChunk::ConstPtr> msgs;
  {
    std::lock_guard<std::mutex> lock(msgs_mutex_);
    for (const auto& kv : msgs_) msgs.push_back(kv.second);
  }
  ROS_DEBUG("%s: %s subscribed to %s: re-sending %zu chunks", name_.c_str(),
            pub.getSubscriberName().c_str(), pub.getTopic().c_str(), msgs.size());
  for (const RasterChunk::ConstPtr& m : msgs) {
    if (stopping_) return;
    pub.publish(m);
  }
}

void MapServer::publishMapCloud(const std::vector<PlanCentre>& centres) {
  const ros::WallTime now = ros::WallTime::now();
  {
    std::lock_guard<std::mutex> lock(msgs_mutex_);
    // Rebuilt when the chunks changed or the vehicle moved by a tenth of the radius.
    bool moved = centres.size() != cloud_centres_.size();
    for (size_t i = 0; !moved && i < centres.size(); ++i) {
      moved = (centres[i] - cloud_centres_[i]).norm() > 0.1 * options_.map_cloud_radius_m;
    }
    if (!(cloud_dirty_ || moved) ||
        (now - last_cloud_time_).toSec() < options_.map_cloud_period_s) {
      return;
    }
    cloud_dirty_ = false;
    cloud_centres_ = centres;
    last_cloud_time_ = now;
  }
  CloudData cloud;
  std::vector<float> sigma;
  buildMapCloud(engine_->held(), engine_->store()->geometry(), centres, options_.map_cloud_radius_m,
                cloud, sigma);
  auto msg = boost::make_shared<sensor_msgs::PointCloud2>();
  toMsg(cloud, *msg, "sigma", sigma);
  msg->header.frame_id = options_.map_frame;
  msg->header.stamp = ros::Time::now();
  msg->is_dense = true;
  cloud_pub_.publish(sensor_msgs::PointCloud2::ConstPtr(msg));
}

}  // namespace node
}  // namespace gmm_localization
