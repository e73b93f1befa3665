#include "gmm_localization/ros/map_server_client.h"

#include <iterator>
#include <set>
#include <sstream>

#include "gmm_localization/ros/chunk_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

/// The publisher's node name from a connection header; empty when there is none.
std::string publisherOf(const boost::shared_ptr<ros::M_string>& header) {
  if (!header) return {};
  auto it = header->find("callerid");
  return it == header->end() ? std::string() : it->second;
}

std::set<ChunkId> listed(const MapIndex& index) {
  std::set<ChunkId> ids;
  const size_t n = std::min(index.chunk_x.size(), index.chunk_y.size());
  for (size_t i = 0; i < n; ++i) ids.insert({index.chunk_x[i], index.chunk_y[i]});
  return ids;
}

}  // namespace

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

MapServerClient::MapServerClient(double publisher_timeout_s)
    : publisher_timeout_s_(publisher_timeout_s > 0.0 ? publisher_timeout_s
                                                     : kDefaultPublisherTimeoutS) {}

MapServerClient::ChunkVerdict MapServerClient::onChunk(const RasterChunk::ConstPtr& msg,
                                                       std::string* error) {
  return onChunk(msg, std::string(), ros::WallTime::now(), error);
}

MapServerClient::ChunkVerdict MapServerClient::onChunk(
    const ros::MessageEvent<const RasterChunk>& event, std::string* error) {
  return onChunk(event.getConstMessage(), publisherOf(event.getConnectionHeaderPtr()),
                 ros::WallTime::now(), error);
}

MapServerClient::ChunkVerdict MapServerClient::onChunk(const RasterChunk::ConstPtr& msg,
                                                       const std::string& publisher,
                                                       ros::WallTime received, std::string* error) {
  if (!msg) {
    if (error) *error = "null chunk message";
    return ChunkVerdict::kInvalid;
  }
  auto chunk = fromMsg(msg);
  if (!chunk) {
    if (error) *error = chunk.error();
    return ChunkVerdict::kInvalid;
  }
  const ChunkId id{msg->chunk_x, msg->chunk_y};
  const bool foreign = index_ && !publisher.empty() && publisher != publisher_;
  if (foreign) {
    // Kept for its own index only once the adopted server is gone (it may take over then).
    if ((received - last_heard_).toSec() < publisher_timeout_s_) {
      if (error) {
        *error =
            "chunk from '" + publisher + "', not from the adopted map server '" + publisher_ + "'";
      }
      return ChunkVerdict::kInvalid;
    }
    waiting_[msg->map_version][id] = {msg->header.stamp, *chunk, publisher};
    return ChunkVerdict::kAdded;
  }
  if (index_ && !publisher.empty()) last_heard_ = received;
  if (!index_ || msg->map_version > index_->map_version) {
    waiting_[msg->map_version][id] = {msg->header.stamp, *chunk, publisher};
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
  held_[id] = {msg->header.stamp, *chunk, publisher};
  map_.insert(*chunk);
  return ChunkVerdict::kAdded;
}

size_t MapServerClient::onIndex(const MapIndex::ConstPtr& index, std::string* error) {
  return onIndex(index, std::string(), ros::WallTime::now(), error);
}

size_t MapServerClient::onIndex(const ros::MessageEvent<const MapIndex>& event,
                                std::string* error) {
  return onIndex(event.getConstMessage(), publisherOf(event.getConnectionHeaderPtr()),
                 ros::WallTime::now(), error);
}

bool MapServerClient::mayAdopt(const MapIndex& index, const std::string& publisher,
                               ros::WallTime received, std::string* error) {
  if (!index_ || publisher == publisher_) return true;
  const double silent_s = (received - last_heard_).toSec();
  if (silent_s >= publisher_timeout_s_) return true;  // the adopted server is gone
  // However new its version: one publisher must not outrank the server this client follows.
  std::ostringstream why;
  why.precision(3);
  why << "map index of version " << index.map_version << " from '" << publisher
      << "' ignored: the adopted map server '" << publisher_ << "' spoke " << silent_s
      << " s ago (another publisher is adopted only after " << publisher_timeout_s_
      << " s of silence)";
  last_ignored_reason_ = why.str();
  ++ignored_indices_;
  if (error) *error = last_ignored_reason_;
  return false;
}

void MapServerClient::keepWaitingFrom(const std::string& publisher) {
  for (auto& [version, chunks] : waiting_) {
    for (auto it = chunks.begin(); it != chunks.end();) {
      const std::string& from = it->second.publisher;
      it = !from.empty() && from != publisher ? chunks.erase(it) : std::next(it);
    }
  }
}

size_t MapServerClient::dropAdopted(const std::string& next_publisher) {
  const size_t dropped = held_.size();
  held_.clear();
  index_.reset();
  map_ = ChunkMap();
  keepWaitingFrom(next_publisher);
  ++publisher_switches_;
  return dropped;
}

size_t MapServerClient::onIndex(const MapIndex::ConstPtr& index, const std::string& publisher,
                                ros::WallTime received, std::string* error) {
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
  if (!mayAdopt(*index, publisher, received, error)) return 0;
  size_t dropped = 0;
  if (index_ && publisher != publisher_) {
    dropped += dropAdopted(publisher);  // took over from a silent server: a new map
  } else if (!index_) {
    keepWaitingFrom(publisher);  // the first index: only its publisher's chunks may wait
  }
  publisher_ = publisher;
  last_heard_ = received;
  if (index_ &&
      (index->map_version < index_->map_version ||
       (index->map_version == index_->map_version && index->header.stamp < index_->header.stamp))) {
    return 0;  // an older index than the one adopted
  }
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
