// Fuzz target: map tile decoding (decodeTile, core/map/map_format.h), the bytes of a tile_*.gmt
// file the map server reads from disk.
// Each input is decoded twice: as it is (what a corrupt file gives: nearly always a CRC
// failure), and "repaired" - the header's stored payload size and the CRC-32 trailer rewritten
// to match the input - so that mutations reach every check behind the CRC. A decoded tile must
// honour the format's contract: a tile size in [8, 4096], every component within the physical
// bounds, a z summary the manifest reader accepts; and what encodeTile accepts of it must
// decode again with the same cells.
#include <cmath>
#include <cstdint>
#include <vector>

#include "fuzz_check.h"
#include "gmm_localization/core/map/map_format.h"

namespace {

using namespace gmm_localization;

void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

void checkTile(const GmmTile& tile) {
  FUZZ_CHECK(tile.sizeCells() >= 8 && tile.sizeCells() <= 4096, "tile size %d", tile.sizeCells());
  FUZZ_CHECK(tile.cells().size() == size_t(tile.sizeCells()) * tile.sizeCells(), "cell count");
  for (const GaussianMixture1D& g : tile.cells()) {
    for (int j = 0; j < g.size(); ++j) {
      FUZZ_CHECK(checkComponentBounds(g.component(j)).empty(), "component out of bounds");
    }
  }
  const TileInfo info = summarizeTile(tile);
  constexpr double kMaxZ = kMaxMapHeightM + 4.0 * kMaxComponentSigmaM;  // the manifest's bound
  FUZZ_CHECK(std::isfinite(info.z_min_m) && std::isfinite(info.z_max_m) &&
                 info.z_min_m <= info.z_max_m && std::abs(info.z_min_m) <= kMaxZ &&
                 std::abs(info.z_max_m) <= kMaxZ,
             "z summary [%g, %g] the manifest would refuse", info.z_min_m, info.z_max_m);

  // The encoder may refuse a decoded tile (its bounds are tighter, e.g. weights >= 2^-20 before
  // renormalisation); what it accepts must decode to the same cell layout.
  auto encoded = encodeTile(tile);
  if (!encoded) return;
  const TileId id = tile.id();
  auto again =
      decodeTile(encoded->bytes.data(), encoded->bytes.size(), "re-encoded", &id, tile.sizeCells());
  FUZZ_CHECK(again.ok(), "re-encoded tile does not decode: %s", again.error().c_str());
  for (size_t i = 0; i < tile.cells().size(); ++i) {
    FUZZ_CHECK((*again)->cells()[i].size() == tile.cells()[i].size(), "cell %zu changed", i);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto as_is = decodeTile(data, size, "fuzz.gmt");
  if (as_is) checkTile(**as_is);

  constexpr size_t kHeader = 48, kCrc = 4;
  if (size < kHeader + kCrc) return 0;
  std::vector<uint8_t> b(data, data + size);
  put32(&b[44], static_cast<uint32_t>(size - kHeader - kCrc));
  put32(&b[size - kCrc], crc32Of(b.data(), size - kCrc));
  // With the id and size the header declares as the expected ones (readTileFile's call).
  const TileId id{static_cast<int32_t>(b[8] | b[9] << 8 | b[10] << 16 | uint32_t(b[11]) << 24),
                  static_cast<int32_t>(b[12] | b[13] << 8 | b[14] << 16 | uint32_t(b[15]) << 24)};
  const int32_t cells = static_cast<int32_t>(b[16] | b[17] << 8 | b[18] << 16 | b[19] << 24);
  auto repaired = decodeTile(b.data(), b.size(), "fuzz.gmt", &id, cells > 0 ? cells : 0);
  if (repaired) {
    FUZZ_CHECK((*repaired)->id() == id, "tile id differs from the header's");
    checkTile(**repaired);
  }
  return 0;
}
