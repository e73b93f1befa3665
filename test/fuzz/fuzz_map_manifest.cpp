// Fuzz target: map manifest parsing (decodeManifest, core/map/map_format.h), the bytes of a map
// directory's manifest.gmm.
// Each input is decoded as it is and with its CRC-32 trailer rewritten to match (so that
// mutations reach the checks behind the CRC). An accepted manifest must honour the contract
// (geometry within the physical bounds, safe unique tile names, tiles within the extent,
// counts that sum to the tile's cells) and re-encode to the same bytes (the format has one
// encoding per manifest; the georeference flag byte is normalised to 0/1, and a version 1 or 2
// manifest is re-encoded as version 3, a height map). A reflectivity map's definition is within
// checkReflectivityLayer's bounds.
#include <cstdint>
#include <set>
#include <vector>

#include "fuzz_check.h"
#include "gmm_localization/core/map/map_format.h"

namespace {

using namespace gmm_localization;

constexpr size_t kGeoreferenceFlagOffset = 36;

void checkManifest(const MapManifest& m, const uint8_t* data, size_t size) {
  FUZZ_CHECK(checkMapGeometryBounds(m.geometry).empty(), "geometry out of bounds");
  FUZZ_CHECK(m.layer == MapLayer::kHeight || m.layer == MapLayer::kReflectivity, "unknown layer");
  FUZZ_CHECK(m.format_version >= 3 || m.layer == MapLayer::kHeight, "an old manifest not height");
  FUZZ_CHECK(m.layer != MapLayer::kReflectivity || checkReflectivityLayer(m.reflectivity).empty(),
             "reflectivity layer out of bounds");
  std::set<TileId> ids;
  const uint64_t cells = uint64_t(m.geometry.tile_size_cells) * m.geometry.tile_size_cells;
  for (const TileInfo& t : m.tiles) {
    FUZZ_CHECK(ids.insert(t.id).second, "tile listed twice");
    FUZZ_CHECK(checkTileExtent(m.geometry, t.id).empty(), "tile beyond the extent");
    FUZZ_CHECK(!t.file_name.empty() && t.file_name.find('/') == std::string::npos &&
                   t.file_name != "." && t.file_name != "..",
               "unsafe file name");
    uint64_t sum = 0;
    for (uint32_t c : t.cells_by_components) sum += c;
    FUZZ_CHECK(sum == cells, "cell counts");
  }
  const std::vector<uint8_t> again = encodeManifest(m);
  auto back = decodeManifest(again.data(), again.size(), "re-encoded");
  FUZZ_CHECK(back.ok(), "re-encoded manifest does not decode: %s", back.error().c_str());
  FUZZ_CHECK(back->tiles.size() == m.tiles.size(), "tile count changed");
  FUZZ_CHECK(back->layer == m.layer, "layer changed");
  const bool newest = size > 6 && data[4] == kManifestFormatVersion && data[5] == 0;
  if (newest && size > kGeoreferenceFlagOffset && data[kGeoreferenceFlagOffset] <= 1) {
    FUZZ_CHECK(again.size() == size && std::equal(again.begin(), again.end(), data),
               "re-encoded manifest differs from the input");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto as_is = decodeManifest(data, size, "fuzz/manifest.gmm");
  if (as_is) checkManifest(*as_is, data, size);
  if (size < 12) return 0;
  std::vector<uint8_t> b(data, data + size);
  const uint32_t crc = crc32Of(b.data(), size - 4);
  for (int i = 0; i < 4; ++i) b[size - 4 + i] = static_cast<uint8_t>(crc >> (8 * i));
  auto repaired = decodeManifest(b.data(), b.size(), "fuzz/manifest.gmm");
  if (repaired) checkManifest(*repaired, b.data(), b.size());
  return 0;
}
