#include "gmm_localization/ros/chunk_conversion.h"

#include <cmath>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace node {
namespace {

/// Bound on |first z bin| and |first z bin + stored bins| of any cell span, in any layer's z
/// units: 2^24 bins are 168 km at 1 cm steps, far beyond kMaxMapHeightM, and keep every
/// difference of a z bin and a span start (MapChunk::spanValue, the search's z loops) far
/// inside int32.
constexpr int64_t kMaxAbsZBin = int64_t{1} << 24;

/// The smallest component sigma the map format encodes (map_format.h: ln sigma uniform in
/// [ln 1e-4 m, ln 1e4 m]; encodeTile refuses smaller ones, decodeTile cannot produce them), so
/// the smallest any map server sends. A smaller positive sigma is no map's: 1 / sigma
/// overflows float from about 3e-39 m (MixtureLogTerms::inv_sigma = inf, a NaN log-likelihood).
constexpr float kMinComponentSigmaM = 1e-4f;

/// Empty when component j of cell i is within the map format's bounds, else why, naming the
/// cell (index and x, y within the chunk), the component and the field.
std::string checkComponent(const GaussianComponent& g, size_t i, int cells, int j) {
  const char* why = nullptr;
  if (!std::isfinite(g.weight)) {
    why = "weight is not finite";
  } else if (!std::isfinite(g.mean_m)) {
    why = "mean is not finite";
  } else if (!std::isfinite(g.sigma_m)) {
    why = "sigma is not finite";
  } else if (!(g.weight > 0.f && g.weight <= 1.0001f)) {
    why = "weight outside (0, 1.0001]";
  } else if (!(std::abs(g.mean_m) <= kMaxMapHeightM)) {
    why = "mean beyond the map format's height bound";
  } else if (!(g.sigma_m >= kMinComponentSigmaM)) {
    why = "sigma below the map format's smallest, 1e-4 m";
  } else if (!(g.sigma_m <= kMaxComponentSigmaM)) {
    why = "sigma beyond the map format's largest";
  } else {
    return {};
  }
  std::ostringstream s;
  s << "cell " << i << " (x " << i % cells << ", y " << i / cells << ") has an invalid component "
    << j << " (weight " << g.weight << ", mean " << g.mean_m << " m, sigma " << g.sigma_m
    << " m): " << why;
  return s.str();
}

}  // namespace

void toMsg(const MapChunk& chunk, uint64_t map_version, const std::string& frame_id,
           const ros::Time& stamp, RasterChunk& msg) {
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.chunk_x = chunk.id().x;
  msg.chunk_y = chunk.id().y;
  msg.shift = chunk.shift();
  msg.map_version = map_version;
  const size_t n_spans = 2 * static_cast<size_t>(chunk.cells()) * chunk.cells() + 2;
  size_t total = 0;
  for (int k = 0; k < chunk.numLayers(); ++k) total += chunk.layer(k).value_count;
  msg.spans.resize(n_spans * chunk.numLayers());
  msg.values.resize(total);
  msg.layers.resize(chunk.numLayers());
  size_t offset = 0;
  for (int k = 0; k < chunk.numLayers(); ++k) {
    const RasterLayer& L = chunk.layer(k);
    ChunkLayer& out = msg.layers[k];
    out.z_shift = L.z_shift;
    out.spans_start = k * n_spans;
    out.values_start = offset;
    out.value_count = L.value_count;
    std::copy(L.spans, L.spans + n_spans, msg.spans.begin() + k * n_spans);
    std::copy(L.values, L.values + L.value_count, msg.values.begin() + offset);
    offset += L.value_count;
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
  const size_t n_spans = 2 * plane + 2;
  std::vector<RasterLayer> layers;
  for (size_t k = 0; k < msg->layers.size(); ++k) {
    const ChunkLayer& in = msg->layers[k];
    const std::string which = "layer " + std::to_string(k);
    if (in.z_shift < 0 || in.z_shift > 16) return R::failure(which + " has an invalid z_shift");
    if (in.spans_start > msg->spans.size() || n_spans > msg->spans.size() - in.spans_start) {
      return R::failure(which + " overruns the spans array");
    }
    if (in.values_start > msg->values.size() ||
        in.value_count > msg->values.size() - in.values_start) {
      return R::failure(which + " overruns the values array");
    }
    // Every span must lie inside the layer's values, in increasing order, and its z bins within
    // +-kMaxAbsZBin (checked in int64, before any int32 arithmetic on them).
    const uint32_t* spans = msg->spans.data() + in.spans_start;
    for (size_t i = 0; i + 1 < n_spans / 2; ++i) {
      if (spans[2 * i + 2] < spans[2 * i] || spans[2 * i + 2] > in.value_count) {
        return R::failure(which + " has an inconsistent span at cell " + std::to_string(i));
      }
      const int64_t first = static_cast<int32_t>(spans[2 * i + 1]);
      const int64_t end = first + (int64_t{spans[2 * i + 2]} - int64_t{spans[2 * i]});
      if (first < -kMaxAbsZBin || end > kMaxAbsZBin) {
        return R::failure(which + " cell " + std::to_string(i) + " has z bins [" +
                          std::to_string(first) + ", " + std::to_string(end) + ") outside +-" +
                          std::to_string(kMaxAbsZBin));
      }
    }
    if (spans[0] != 0 || spans[n_spans - 2] != in.value_count) {
      return R::failure(which + " spans do not cover its values");
    }
    RasterLayer L;
    L.z_shift = in.z_shift;
    L.spans = spans;
    L.values = msg->values.data() + in.values_start;
    L.value_count = in.value_count;
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
      const std::string bad = checkComponent(g, i, chunk->cells(), j);
      if (!bad.empty()) return R::failure(bad);
      mixtures[i].add(g);
    }
  }
  if (c != msg->components.size()) return R::failure("components array too long");
  // The layers point into the message's arrays: the chunk holds the message.
  // (ROS messages use boost::shared_ptr: a deleter that holds a copy bridges the two.)
  chunk->setLayers(std::move(layers),
                   std::shared_ptr<const void>(msg.get(), [keep = msg](const void*) {}));
  chunk->setMixtures(std::move(mixtures));
  return MapChunkConstPtr(chunk);
}

}  // namespace node
}  // namespace gmm_localization
