#include "gmm_localization/ros/chunk_conversion.h"

#include <cmath>

namespace gmm_localization {
namespace node {

void toMsg(const MapChunk& chunk, uint64_t map_version, const std::string& frame_id,
           const ros::Time& stamp, RasterChunk& msg) {
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.chunk_x = chunk.id().x;
  msg.chunk_y = chunk.id().y;
  msg.shift = chunk.shift();
  msg.map_version = map_version;
  const size_t plane = static_cast<size_t>(chunk.cells()) * chunk.cells();
  size_t total = 0;
  for (int k = 0; k < chunk.numLayers(); ++k) total += chunk.layer(k).nz * plane;
  msg.data.resize(total);
  msg.layers.resize(chunk.numLayers());
  size_t offset = 0;
  for (int k = 0; k < chunk.numLayers(); ++k) {
    const RasterLayer& L = chunk.layer(k);
    ChunkLayer& out = msg.layers[k];
    out.z_lo = L.z_lo;
    out.nz = L.nz;
    out.z_shift = L.z_shift;
    out.offset = offset;
    const size_t bytes = static_cast<size_t>(L.nz) * plane;
    if (bytes > 0) std::copy(L.data, L.data + bytes, msg.data.begin() + offset);
    offset += bytes;
  }
  msg.component_count.assign(chunk.mixtures().size(), 0);
  msg.components.clear();
  for (size_t i = 0; i < chunk.mixtures().size(); ++i) {
    const GaussianMixture1D& g = chunk.mixtures()[i];
    msg.component_count[i] = static_cast<uint8_t>(g.size());
    for (int j = 0; j < g.size(); ++j) {
      msg.components.push_back(g.component(j).weight);
      msg.components.push_back(g.component(j).mean_m);
      msg.components.push_back(g.component(j).sigma_m);
    }
  }
}

Result<MapChunkConstPtr> fromMsg(const RasterChunk::ConstPtr& msg) {
  using R = Result<MapChunkConstPtr>;
  if (!msg) return R::failure("null chunk message");
  if (msg->shift < 4 || msg->shift > 10) {
    return R::failure("chunk shift " + std::to_string(msg->shift) + " outside [4, 10]");
  }
  auto chunk = std::make_shared<MapChunk>(ChunkId{msg->chunk_x, msg->chunk_y}, msg->shift);
  const size_t plane = static_cast<size_t>(chunk->cells()) * chunk->cells();
  std::vector<RasterLayer> layers;
  for (size_t k = 0; k < msg->layers.size(); ++k) {
    const ChunkLayer& in = msg->layers[k];
    if (in.nz < 0 || in.z_shift < 0 || in.z_shift > 16) {
      return R::failure("layer " + std::to_string(k) + " has invalid nz or z_shift");
    }
    const uint64_t bytes = static_cast<uint64_t>(in.nz) * plane;
    if (in.offset > msg->data.size() || bytes > msg->data.size() - in.offset) {
      return R::failure("layer " + std::to_string(k) + " overruns the chunk data (" +
                        std::to_string(msg->data.size()) + " bytes)");
    }
    RasterLayer L;
    L.z_lo = in.z_lo;
    L.nz = in.nz;
    L.z_shift = in.z_shift;
    L.data = msg->data.data() + in.offset;
    layers.push_back(L);
  }
  if (layers.empty()) return R::failure("chunk has no layers");
  if (!msg->component_count.empty() && msg->component_count.size() != plane) {
    return R::failure("component_count has " + std::to_string(msg->component_count.size()) +
                      " cells, expected " + std::to_string(plane));
  }
  std::vector<GaussianMixture1D> mixtures(msg->component_count.empty() ? 0 : plane);
  size_t c = 0;
  for (size_t i = 0; i < mixtures.size(); ++i) {
    const int k = msg->component_count[i];
    if (k > kMaxMixtureComponents) return R::failure("a cell has more than 3 components");
    for (int j = 0; j < k; ++j, c += 3) {
      if (c + 3 > msg->components.size()) return R::failure("components array too short");
      const GaussianComponent g{msg->components[c], msg->components[c + 1], msg->components[c + 2]};
      if (!(g.weight > 0.f && g.weight <= 1.0001f && g.sigma_m > 0.f && std::isfinite(g.mean_m))) {
        return R::failure("cell " + std::to_string(i) + " has an invalid component");
      }
      mixtures[i].add(g);
    }
  }
  if (c != msg->components.size()) return R::failure("components array too long");
  // The layers point into msg->data: the chunk holds the message.
  // (ROS messages use boost::shared_ptr: a deleter that holds a copy bridges the two.)
  chunk->setLayers(std::move(layers),
                   std::shared_ptr<const void>(msg.get(), [keep = msg](const void*) {}));
  chunk->setMixtures(std::move(mixtures));
  return MapChunkConstPtr(chunk);
}

}  // namespace node
}  // namespace gmm_localization
