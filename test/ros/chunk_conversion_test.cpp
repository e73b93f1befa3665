// MapChunk <-> RasterChunk (chunk_conversion.h): exact round trip, zero-copy fromMsg that keeps
// the message alive, and every malformed message (arrays too short, spans that disagree with
// the values, invalid mixtures) rejected with a reason.
#include "gmm_localization/ros/chunk_conversion.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <boost/make_shared.hpp>

#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace node {
namespace {

RasterOptions options() {
  RasterOptions o;
  o.chunk_shift = 4;
  o.num_layers = 3;
  o.z_coarsening_period = 1;
  return o;
}

/// A random map over tiles (0..1, 0..1) of 16 cells: 0-2 components per cell.
GmmMap randomMap(uint32_t seed) {
  MapGeometry g;
  g.tile_size_cells = 16;
  GmmMap map(g);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> mean(-1.f, 4.f), sigma(0.03f, 0.5f), w(0.2f, 0.8f);
  std::uniform_int_distribution<int> k(0, 2);
  for (int tx = 0; tx < 2; ++tx) {
    for (int ty = 0; ty < 2; ++ty) {
      auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, 16);
      for (GaussianMixture1D& cell : tile->cells()) {
        const int n = k(rng);
        const float w0 = w(rng);
        if (n == 1) cell.add({1.f, mean(rng), sigma(rng)});
        if (n == 2) {
          cell.add({w0, mean(rng), sigma(rng)});
          cell.add({1.f - w0, mean(rng), sigma(rng)});
        }
      }
      map.insert(tile);
    }
  }
  return map;
}

MapChunkConstPtr rasterized(ChunkId id = {0, 0}) {
  auto r = rasterizeChunk(randomMap(3), id, options());
  EXPECT_TRUE(r.ok()) << r.error();
  return *r;
}

RasterChunk::Ptr toMessage(const MapChunk& chunk) {
  auto msg = boost::make_shared<RasterChunk>();
  toMsg(chunk, 17, "map", ros::Time(12, 34), *msg);
  return msg;
}

TEST(ChunkConversion, RoundTripIsExact) {
  const MapChunkConstPtr chunk = rasterized({1, 0});
  const RasterChunk::Ptr msg = toMessage(*chunk);
  EXPECT_EQ(msg->chunk_x, 1);
  EXPECT_EQ(msg->chunk_y, 0);
  EXPECT_EQ(msg->shift, 4);
  EXPECT_EQ(msg->map_version, 17u);
  EXPECT_EQ(msg->header.frame_id, "map");
  EXPECT_EQ(msg->header.stamp, ros::Time(12, 34));
  ASSERT_EQ(msg->layers.size(), 4u);
  auto back = fromMsg(msg);
  ASSERT_TRUE(back.ok()) << back.error();
  const MapChunk& b = **back;
  EXPECT_EQ(b.id(), chunk->id());
  EXPECT_TRUE(b.sameTables(*chunk));
  // Value by value too, over a z range wider than the map's.
  size_t nonzero = 0;
  for (int k = 0; k < b.numLayers(); ++k) {
    EXPECT_EQ(b.layer(k).z_shift, chunk->layer(k).z_shift);
    for (int32_t zb = -30; zb < 60; ++zb) {
      for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 16; ++x) {
          ASSERT_EQ(b.value(k, zb, x, y), chunk->value(k, zb, x, y));
          nonzero += b.value(k, zb, x, y) > 0;
        }
      }
    }
  }
  EXPECT_GT(nonzero, 1000u) << "the test map must exercise the tables";
  EXPECT_EQ(b.mixtures(), chunk->mixtures());
  EXPECT_EQ(b.bytes(), chunk->bytes());
}

TEST(ChunkConversion, FromMsgSharesTheMessageAndKeepsItAlive) {
  RasterChunk::Ptr msg = toMessage(*rasterized());
  const RasterChunk* raw = msg.get();
  auto chunk = fromMsg(msg);
  ASSERT_TRUE(chunk.ok());
  EXPECT_GT(msg.use_count(), 1) << "the chunk holds the message";
  for (int k = 0; k < (*chunk)->numLayers(); ++k) {
    const RasterLayer& L = (*chunk)->layer(k);
    EXPECT_EQ(L.spans, msg->spans.data() + msg->layers[k].spans_start) << "layer " << k;
    EXPECT_EQ(L.values, msg->values.data() + msg->layers[k].values_start) << "layer " << k;
  }
  ASSERT_FALSE(msg->values.empty());
  const uint8_t first = msg->values.front();
  msg.reset();  // the chunk alone keeps the message alive
  EXPECT_EQ((*chunk)->layer(0).values[0], first);
  EXPECT_EQ((*chunk)->layer(0).values, raw->values.data() + raw->layers[0].values_start);
}

TEST(ChunkConversion, EmptyChunkRoundTrips) {
  auto chunk = rasterizeChunk(randomMap(3), {7, 7}, options());  // no tile there
  ASSERT_TRUE(chunk.ok());
  auto msg = toMessage(**chunk);
  EXPECT_TRUE(msg->values.empty());
  auto back = fromMsg(msg);
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ((*back)->value(0, 0, 3, 3), 0);
  EXPECT_TRUE((*back)->sameTables(**chunk));
  EXPECT_EQ((*back)->mixtures(), (*chunk)->mixtures());
}

/// fromMsg of a copy of a good message after `mutate` fails with a reason containing `what`.
template <typename F>
void expectRejected(F mutate, const std::string& what) {
  auto msg = boost::make_shared<RasterChunk>(*toMessage(*rasterized()));
  mutate(*msg);
  auto r = fromMsg(msg);
  ASSERT_FALSE(r.ok()) << "accepted a message that should fail with '" << what << "'";
  EXPECT_NE(r.error().find(what), std::string::npos) << r.error();
}

/// Index in msg.spans of the first cell of layer k with a non-empty span.
size_t firstNonEmptyCell(const RasterChunk& m, size_t k) {
  const size_t base = m.layers[k].spans_start;
  for (size_t i = 0;; ++i) {
    if (m.spans[base + 2 * i + 2] > m.spans[base + 2 * i]) return i;
  }
}

TEST(ChunkConversion, MalformedMessagesAreRejected) {
  EXPECT_FALSE(fromMsg(RasterChunk::ConstPtr()).ok());
  expectRejected([](RasterChunk& m) { m.shift = 3; }, "shift");
  expectRejected([](RasterChunk& m) { m.shift = 11; }, "shift");
  expectRejected([](RasterChunk& m) { m.layers.clear(); }, "no layers");
  expectRejected([](RasterChunk& m) { m.layers[1].z_shift = -1; }, "z_shift");
  expectRejected([](RasterChunk& m) { m.layers[1].z_shift = 40; }, "z_shift");
  // Arrays too short for the layers that point into them.
  expectRejected([](RasterChunk& m) { m.spans.pop_back(); }, "spans");
  expectRejected([](RasterChunk& m) { m.layers.back().spans_start += 1; }, "spans");
  expectRejected([](RasterChunk& m) { m.layers[0].spans_start = ~uint64_t{0}; }, "spans");
  expectRejected([](RasterChunk& m) { m.values.pop_back(); }, "values");
  expectRejected([](RasterChunk& m) { m.layers[0].values_start = ~uint64_t{0}; }, "values");
  expectRejected([](RasterChunk& m) { m.layers[0].value_count += 1000000; }, "values");
  // Spans that disagree with the values: decreasing, beyond the layer, not covering it.
  expectRejected(
      [](RasterChunk& m) {
        const size_t i = firstNonEmptyCell(m, 0);
        const size_t base = m.layers[0].spans_start;
        std::swap(m.spans[base + 2 * i], m.spans[base + 2 * i + 2]);
      },
      "span");
  expectRejected(
      [](RasterChunk& m) {
        const size_t base = m.layers[0].spans_start;
        const size_t last = 2 * 16 * 16;  // the closing offset
        m.spans[base + last] = m.layers[0].value_count + 1;
      },
      "span");
  expectRejected([](RasterChunk& m) { m.layers[0].value_count -= 1; }, "span");
  // Mixtures.
  expectRejected([](RasterChunk& m) { m.component_count.pop_back(); }, "component_count");
  expectRejected([](RasterChunk& m) { m.components.pop_back(); }, "components array");
  expectRejected([](RasterChunk& m) { m.components.push_back(1.f); }, "too long");
  expectRejected(
      [](RasterChunk& m) {
        for (uint8_t& k : m.component_count) {
          if (k > 0) {
            k = 4;
            break;
          }
        }
      },
      "more than 3");
  expectRejected([](RasterChunk& m) { m.components.at(2) = 0.f; }, "invalid component");  // sigma
  expectRejected([](RasterChunk& m) { m.components.at(0) = -0.5f; }, "invalid component");
  expectRejected([](RasterChunk& m) { m.components.at(1) = NAN; }, "invalid component");
}

TEST(ChunkConversion, ExtremeIntegerAndComponentFieldsAreRejected) {
  // A first z bin at the int32 extremes: (zb >> z_shift) - first would overflow.
  for (uint32_t first : {0x80000000u, 0x7fffffffu, 0x80000001u, uint32_t{1} << 24}) {
    expectRejected(
        [first](RasterChunk& m) {
          const size_t i = firstNonEmptyCell(m, 0);
          m.spans[m.layers[0].spans_start + 2 * i + 1] = first;
        },
        "z bins");
  }
  // The same for a cell with an empty span (no values, but still a z bin start).
  expectRejected([](RasterChunk& m) { m.spans[m.layers[2].spans_start + 1] = 0x80000000u; },
                 "layer 2 cell 0 has z bins");
  // Bins near (but within) the bound are accepted.
  {
    auto msg = boost::make_shared<RasterChunk>(*toMessage(*rasterized()));
    const size_t i = firstNonEmptyCell(*msg, 0);
    msg->spans[msg->layers[0].spans_start + 2 * i + 1] = static_cast<uint32_t>(-(1 << 23));
    EXPECT_TRUE(fromMsg(msg).ok()) << fromMsg(msg).error();
  }
  // Components beyond the physical bounds of the map format.
  expectRejected([](RasterChunk& m) { m.components.at(1) = 7e4f; }, "mean 70000");
  expectRejected([](RasterChunk& m) { m.components.at(1) = -INFINITY; }, "invalid component");
  expectRejected([](RasterChunk& m) { m.components.at(2) = INFINITY; }, "invalid component");
  expectRejected([](RasterChunk& m) { m.components.at(2) = 5e3f; }, "sigma 5000");
  expectRejected([](RasterChunk& m) { m.components.at(0) = NAN; }, "invalid component");
}

/// Index in msg.components of component j of the first cell with at least `k` components; the
/// cell's index in `cell`.
size_t componentOfFirstCellWith(const RasterChunk& m, int k, int j, size_t* cell) {
  size_t c = 0;
  for (size_t i = 0; i < m.component_count.size(); ++i) {
    if (m.component_count[i] >= k) {
      *cell = i;
      return c + 3 * j;
    }
    c += 3 * m.component_count[i];
  }
  ADD_FAILURE() << "no cell with " << k << " components";
  return 0;
}

// Fuzz reproducer test/fuzz/regressions/raster_chunk/nan_log_terms_subnormal_sigma: a
// two-component cell whose first sigma is 1e-39 m (subnormal) was accepted (sigma > 0), and
// MixtureLogTerms then held 1 / sigma = inf and a NaN log-likelihood at the mean. Now every
// sigma below the map format's smallest (1e-4 m) and every non-finite field is rejected, naming
// the cell, the component and the field.
TEST(ChunkConversion, SigmaBelowTheFormatsSmallestAndNonFiniteFieldsAreRejected) {
  const RasterChunk::Ptr good = toMessage(*rasterized());
  size_t cell = 0;
  const size_t c = componentOfFirstCellWith(*good, 2, 0, &cell);
  const std::string name = "cell " + std::to_string(cell) + " (x " + std::to_string(cell % 16) +
                           ", y " + std::to_string(cell / 16) + ") has an invalid component 0";
  auto rejected = [&](size_t field, float value, const std::string& why) {
    auto msg = boost::make_shared<RasterChunk>(*good);
    msg->components.at(c + field) = value;
    auto r = fromMsg(msg);
    ASSERT_FALSE(r.ok()) << "accepted component field " << field << " = " << value;
    EXPECT_NE(r.error().find(name), std::string::npos) << r.error();
    EXPECT_NE(r.error().find(why), std::string::npos) << r.error();
  };
  rejected(2, 1e-39f, "sigma below the map format's smallest, 1e-4 m");  // the reproducer
  EXPECT_NE(std::fpclassify(1e-39f), FP_NORMAL);
  rejected(2, std::numeric_limits<float>::denorm_min(), "sigma below");
  rejected(2, std::nextafter(1e-4f, 0.f), "sigma below");
  rejected(2, -1e-3f, "sigma below");
  rejected(2, NAN, "sigma is not finite");
  rejected(2, INFINITY, "sigma is not finite");
  rejected(0, INFINITY, "weight is not finite");
  rejected(0, NAN, "weight is not finite");
  rejected(0, 1.5f, "weight outside");
  rejected(1, -INFINITY, "mean is not finite");
  rejected(1, NAN, "mean is not finite");
  rejected(1, 2e4f, "mean beyond");
  // The format's smallest sigma itself is accepted, with finite log terms (as the search reads
  // the cell: at the mean and far from it).
  auto msg = boost::make_shared<RasterChunk>(*good);
  msg->components.at(c + 2) = 1e-4f;
  auto ok = fromMsg(msg);
  ASSERT_TRUE(ok.ok()) << ok.error();
  const int lx = static_cast<int>(cell % 16), ly = static_cast<int>(cell / 16);
  const GaussianMixture1D& g = (*ok)->mixture(lx, ly);
  ASSERT_EQ(g.size(), good->component_count[cell]);
  for (double z : {double{g.component(0).mean_m}, double{g.component(1).mean_m}, 1e4, -1e4}) {
    EXPECT_FALSE(std::isnan((*ok)->logTerms(lx, ly).logLikelihood(z))) << z;
    EXPECT_FALSE(std::isnan(g.logLikelihood(z))) << z;
  }
  EXPECT_TRUE(std::isfinite((*ok)->logTerms(lx, ly).inv_sigma[0]));
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
