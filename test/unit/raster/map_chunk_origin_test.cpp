// MapChunk::origin() is id * 2^shift for every chunk id, negative ones included (it used to
// left-shift negative values, which is undefined behaviour).

#include <cstdint>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/map_chunk.h"

namespace gmm_localization {
namespace {

TEST(MapChunkOrigin, IsIdTimesChunkCellsForAllIds) {
  const int32_t lo = std::numeric_limits<int32_t>::min();
  const int32_t hi = std::numeric_limits<int32_t>::max();
  std::vector<int32_t> ids = {0, 1, -1, 2, -2, 1000, -1000, lo, lo + 1, hi, hi - 1};
  std::mt19937 rng(5);
  std::uniform_int_distribution<int32_t> any(lo, hi);
  for (int i = 0; i < 200; ++i) ids.push_back(any(rng));
  for (int shift = 4; shift <= 10; ++shift) {
    for (int32_t x : ids) {
      for (int32_t y : {int32_t{0}, int32_t{-3}, x}) {
        const MapChunk c({x, y}, shift);
        const CellIndex o = c.origin();
        // Reference in exact integer arithmetic: |id| * 2^10 < 2^42 fits int64.
        EXPECT_EQ(o.x, int64_t{x} * (int64_t{1} << shift)) << x << " " << shift;
        EXPECT_EQ(o.y, int64_t{y} * (int64_t{1} << shift)) << y << " " << shift;
        // The chunk's first cell maps back to the chunk (arithmetic shift = floor division).
        EXPECT_EQ(o.x >> shift, x);
        EXPECT_EQ(o.y >> shift, y);
        EXPECT_EQ((o.x + c.cells() - 1) >> shift, x);
      }
    }
  }
  EXPECT_EQ(MapChunk({-1, -2}, 7).origin(), (CellIndex{-128, -256}));
}

}  // namespace
}  // namespace gmm_localization
