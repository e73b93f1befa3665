#include "gmm_localization/ros/map_server_client.h"

#include <set>

#include "gmm_localization/ros/chunk_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

std::set<ChunkId> listed(const MapIndex& index) {
  std::set<ChunkId> ids;
  const size_t n = std::min(index.chunk_x.size(), index.chunk_y.size());
  for (size_t i = 0; i < n; ++i) ids.insert({index.chunk_x[i], index.chunk_y[i]});
  return ids;
}

}  // namespace

MapGeometry geometryOf(const MapIndex& index) {
  MapGeometry g;
  g.resolution_m = index.resolution_m;
  g.tile_size_cells = index.tile_size_cells;
  g.origin_x_m = index.origin_x_m;
  g.origin_y_m = index.origin_y_m;
  return g;
}

RasterOptions rasterOptionsOf(const MapIndex& index) {
  RasterOptions o;
  o.z_step_m = index.z_step_m;
  o.ll_floor = index.ll_floor;
  o.ll_ceiling = index.ll_ceiling;
  o.num_layers = index.num_layers;
  o.z_coarsening_period = index.z_coarsening_period;
  o.chunk_shift = index.chunk_shift;
  return o;
}

bool MapServerClient::matchesIndex(const RasterChunk& msg, std::string* error) const {
  if (msg.shift != index_->chunk_shift) {
    if (error) {
      *error = "chunk shift " + std::to_string(msg.shift) + " differs from the index's " +
               std::to_string(index_->chunk_shift);
    }
    return false;
  }
  if (static_cast<int>(msg.layers.size()) != index_->num_layers + 1) {
    if (error) {
      *error = "chunk has " + std::to_string(msg.layers.size()) + " layers, the index says " +
               std::to_string(index_->num_layers + 1);
    }
    return false;
  }
  return true;
}

MapServerClient::ChunkVerdict MapServerClient::onChunk(const RasterChunk::ConstPtr& msg,
                                                       std::string* error) {
  auto chunk = fromMsg(msg);
  if (!chunk) {
    if (error) *error = chunk.error();
    return ChunkVerdict::kInvalid;
  }
  const ChunkId id{msg->chunk_x, msg->chunk_y};
  if (!index_ || msg->map_version > index_->map_version) {
    waiting_[msg->map_version][id] = {msg->header.stamp, *chunk};
    return ChunkVerdict::kAdded;
  }
  if (msg->map_version < index_->map_version) {
    if (error) *error = "chunk of an older map version";
    return ChunkVerdict::kStale;
  }
  if (!matchesIndex(*msg, error)) return ChunkVerdict::kInvalid;
  if (msg->header.stamp <= index_->header.stamp && listed(*index_).count(id) == 0) {
    if (error) *error = "chunk evicted by a newer index";
    return ChunkVerdict::kStale;
  }
  held_[id] = {msg->header.stamp, *chunk};
  map_.insert(*chunk);
  return ChunkVerdict::kAdded;
}

size_t MapServerClient::onIndex(const MapIndex::ConstPtr& index) {
  if (!index) return 0;
  if (index_ &&
      (index->map_version < index_->map_version ||
       (index->map_version == index_->map_version && index->header.stamp < index_->header.stamp))) {
    return 0;  // an older index than the one adopted
  }
  size_t dropped = 0;
  const bool new_version = !index_ || index->map_version != index_->map_version;
  index_ = index;
  if (new_version) {
    dropped += held_.size();
    held_.clear();
    map_ = ChunkMap(geometryOf(*index), rasterOptionsOf(*index));
    auto it = waiting_.find(index->map_version);
    if (it != waiting_.end()) held_ = std::move(it->second);  // checked below like the others
    waiting_.erase(waiting_.begin(), waiting_.upper_bound(index->map_version));
  }
  const std::set<ChunkId> ids = listed(*index);
  for (auto it = held_.begin(); it != held_.end();) {
    const bool evicted = ids.count(it->first) == 0 && it->second.stamp <= index->header.stamp;
    const bool mismatch = it->second.chunk->shift() != index->chunk_shift ||
                          it->second.chunk->numLayers() != index->num_layers + 1;
    if (evicted || mismatch) {
      ++dropped;
      it = held_.erase(it);
    } else {
      ++it;
    }
  }
  map_.clear();
  for (const auto& kv : held_) map_.insert(kv.second.chunk);
  return dropped;
}

bool MapServerClient::complete() const {
  if (!index_) return false;
  for (const ChunkId& id : listed(*index_)) {
    if (held_.count(id) == 0) return false;
  }
  return true;
}

}  // namespace node
}  // namespace gmm_localization
