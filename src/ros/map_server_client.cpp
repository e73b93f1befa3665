#include "gmm_localization/ros/map_server_client.h"

#include <cmath>
#include <set>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"
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

std::string validateIndex(const MapIndex& index) {
  const MapGeometry g = geometryOf(index);
  const std::string geometry_error = checkMapGeometryBounds(g);
  if (!geometry_error.empty()) return "invalid geometry: " + geometry_error;
  const std::string raster_error = rasterOptionsOf(index).validate();
  if (!raster_error.empty()) return "invalid raster options: " + raster_error;
  if (index.chunk_x.size() != index.chunk_y.size()) {
    return "chunk_x lists " + std::to_string(index.chunk_x.size()) + " ids, chunk_y " +
           std::to_string(index.chunk_y.size());
  }
  // Every chunk within the map format's extent (one chunk of slack for chunks straddling it).
  const double chunk_m = g.resolution_m * static_cast<double>(1 << index.chunk_shift);
  const double max_chunk = (kMaxMapExtentM + chunk_m) / chunk_m;
  for (size_t i = 0; i < index.chunk_x.size(); ++i) {
    const double far_x =
        std::max(std::abs(double(index.chunk_x[i])), std::abs(double(index.chunk_x[i]) + 1.0));
    const double far_y =
        std::max(std::abs(double(index.chunk_y[i])), std::abs(double(index.chunk_y[i]) + 1.0));
    if (far_x > max_chunk || far_y > max_chunk) {
      return "chunk (" + std::to_string(index.chunk_x[i]) + ", " +
             std::to_string(index.chunk_y[i]) + ") lies beyond " + std::to_string(kMaxMapExtentM) +
             " m of the map origin";
    }
  }
  const double bound = kMaxMapExtentM + g.tileSizeM();
  const double ext[] = {index.min_x_m - g.origin_x_m, index.max_x_m - g.origin_x_m,
                        index.min_y_m - g.origin_y_m, index.max_y_m - g.origin_y_m};
  for (double e : ext) {
    if (!(std::abs(e) <= bound)) {
      std::ostringstream s;
      s << "map extent x [" << index.min_x_m << ", " << index.max_x_m << "], y [" << index.min_y_m
        << ", " << index.max_y_m << "] m is not finite or beyond " << kMaxMapExtentM
        << " m of the origin";
      return s.str();
    }
  }
  if (index.min_x_m > index.max_x_m || index.min_y_m > index.max_y_m) {
    return "map extent has min > max";
  }
  return {};
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

size_t MapServerClient::onIndex(const MapIndex::ConstPtr& index, std::string* error) {
  if (error) error->clear();
  if (!index) {
    if (error) *error = "null index message";
    ++rejected_indices_;
    return 0;
  }
  const std::string invalid = validateIndex(*index);
  if (!invalid.empty()) {
    // Never adopted: a malformed index (however new its version) leaves the adopted one, and
    // every held or waiting chunk, untouched.
    if (error)
      *error =
          "map index of version " + std::to_string(index->map_version) + " rejected: " + invalid;
    ++rejected_indices_;
    return 0;
  }
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
