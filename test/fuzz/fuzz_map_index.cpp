// Fuzz target: map index messages (gmm_localization/MapIndex) and their adoption by the
// matcher's map client (node::validateIndex and node::MapServerClient, ros/map_server_client.h),
// together with the chunks that arrive around them. The input is a sequence of up to 16
// messages (layout: fuzz_input.h), each preceded by one byte: bit 0 index (1) or chunk (0),
// bits 1-2 the publisher ("", "/map_server", "/other", "/third"), bits 3-7 the wall time since
// the previous message in 0.5 s steps. After every message the client must hold what the
// matcher relies on: an adopted index that validateIndex accepts, and only chunks of its shift
// and layer count (num_layers + 1), readable at every layer the index promises.
#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_check.h"
#include "fuzz_input.h"
#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/ros/map_server_client.h"

namespace {

using namespace gmm_localization;

const char* const kPublishers[] = {"", "/map_server", "/other", "/third"};

void checkClient(const node::MapServerClient& client) {
  if (!client.hasIndex()) {
    FUZZ_CHECK(client.chunks().size() == 0, "chunks without an index");
    return;
  }
  const MapIndex& index = *client.index();
  FUZZ_CHECK(node::validateIndex(index).empty(), "adopted an invalid index");
  const ChunkMap& map = client.chunks();
  for (const auto& kv : map.chunks()) {
    const MapChunk& c = *kv.second;
    FUZZ_CHECK(kv.first == c.id(), "chunk held under another id");
    FUZZ_CHECK(c.shift() == index.chunk_shift, "chunk shift %d, index %d", c.shift(),
               index.chunk_shift);
    FUZZ_CHECK(c.numLayers() == index.num_layers + 1, "chunk has %d layers, index %d + 1",
               c.numLayers(), index.num_layers);
    // The search's reads: each layer the index promises, at the chunk's corner cells, at the
    // z bins of heights across the map format's physical range.
    const CellIndex o = c.origin();
    const int64_t last = c.cells() - 1;
    for (int k = 0; k <= index.num_layers; ++k) {
      for (double z : {-kMaxMapHeightM, -1.0, 0.0, 1.0, kMaxMapHeightM}) {
        const int32_t zb = map.zBin(z);
        for (const CellIndex& cell : {o, CellIndex{o.x + last, o.y + last}}) {
          (void)map.value(k, cell, zb);
          (void)map.mixture(cell);
        }
      }
    }
  }
  (void)client.complete();
  (void)map.bytes();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Reader r(data, size);
  node::MapServerClient client;
  double wall_s = 1000.0;
  std::string error;
  for (int step = 0; step < 16 && r.remaining() > 0; ++step) {
    const uint8_t op = r.get<uint8_t>();
    const std::string publisher = kPublishers[(op >> 1) & 3];
    wall_s += 0.5 * (op >> 3);
    const ros::WallTime received(wall_s);
    if (op & 1) {
      const MapIndex::ConstPtr index = fuzz::readIndex(r);
      const std::string invalid = node::validateIndex(*index);
      const MapIndex::ConstPtr before = client.index();
      const size_t held = client.chunks().size();
      client.onIndex(index, publisher, received, &error);
      if (!invalid.empty()) {
        FUZZ_CHECK(client.index() == before && client.chunks().size() == held,
                   "an invalid index changed the adopted one or the chunks: %s", invalid.c_str());
      }
    } else {
      client.onChunk(fuzz::readChunk(r), publisher, received, &error);
    }
    checkClient(client);
  }
  return 0;
}
