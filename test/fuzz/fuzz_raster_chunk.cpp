// Fuzz target: the raster chunk message reader (node::fromMsg of a gmm_localization/RasterChunk,
// ros/chunk_conversion.h) that wraps every chunk the matcher receives from the map server,
// without a copy. The input chooses every field (layout: fuzz_input.h): id, shift, the layers'
// z shifts and offsets, the spans, values and mixtures. An accepted chunk must be safe to read
// the way the search reads it - every cell of every layer at z bins inside, at the edges of and
// far outside its span, every mixture's log-likelihood - and toMsg of it must read again to the
// same tables.
#include <cmath>
#include <cstdint>

#include "fuzz_check.h"
#include "fuzz_input.h"
#include "gmm_localization/ros/chunk_conversion.h"

namespace {

using namespace gmm_localization;

void readEverything(const MapChunk& chunk) {
  const int cells = chunk.cells();
  unsigned sum = 0;  // keeps the reads
  for (int k = 0; k < chunk.numLayers(); ++k) {
    const RasterLayer& L = chunk.layer(k);
    for (int ly = 0; ly < cells; ++ly) {
      for (int lx = 0; lx < cells; ++lx) {
        const size_t i = static_cast<size_t>(ly) * cells + lx;
        const int32_t first = static_cast<int32_t>(L.spans[2 * i + 1]);
        const int32_t n = static_cast<int32_t>(L.spans[2 * i + 2] - L.spans[2 * i]);
        // Base z bins whose layer-k bin is just before, at, and just past the span, and far away
        // (2^25 base bins: 335 km at the smallest z step, beyond any map's heights).
        const int64_t zs[] = {int64_t{first} - 1,     first,
                              int64_t{first} + n - 1, int64_t{first} + n,
                              -(int64_t{1} << 25),    int64_t{1} << 25};
        for (int64_t z : zs) {
          const int64_t zb = z * (int64_t{1} << L.z_shift);
          if (zb < -(int64_t{1} << 25) || zb > (int64_t{1} << 25)) continue;
          sum += chunk.value(k, static_cast<int32_t>(zb), lx, ly);
        }
      }
    }
  }
  if (chunk.hasMixtures()) {
    for (int ly = 0; ly < cells; ++ly) {
      for (int lx = 0; lx < cells; ++lx) {
        const GaussianMixture1D& g = chunk.mixture(lx, ly);
        if (g.empty()) continue;
        const double z = g.component(0).mean_m;
        const double a = g.logLikelihood(z), b = chunk.logTerms(lx, ly).logLikelihood(z);
        if (std::isnan(a) || std::isnan(b)) {
          for (int j = 0; j < g.size(); ++j) {
            std::fprintf(stderr, "component %d: weight %g mean %g sigma %g\n", j,
                         g.component(j).weight, g.component(j).mean_m, g.component(j).sigma_m);
          }
        }
        FUZZ_CHECK(!std::isnan(a) && !std::isnan(b),
                   "log-likelihood at z = %g of cell (%d, %d): %g (mixture), %g (log terms)", z, lx,
                   ly, a, b);
      }
    }
  }
  (void)chunk.bytes();
  volatile unsigned keep = sum;
  (void)keep;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Reader r(data, size);
  const RasterChunk::ConstPtr msg = fuzz::readChunk(r);
  auto chunk = node::fromMsg(msg);
  if (!chunk) return 0;
  const MapChunk& c = **chunk;
  FUZZ_CHECK(c.shift() >= 4 && c.shift() <= 10, "shift %d", c.shift());
  FUZZ_CHECK(c.numLayers() == static_cast<int>(msg->layers.size()), "layer count");
  FUZZ_CHECK(!c.hasMixtures() || c.mixtures().size() == size_t(c.cells()) * c.cells(),
             "mixture count");
  readEverything(c);

  RasterChunk out;
  node::toMsg(c, msg->map_version, "map", msg->header.stamp, out);
  auto again = node::fromMsg(boost::make_shared<const RasterChunk>(out));
  FUZZ_CHECK(again.ok(), "toMsg's chunk does not read: %s", again.error().c_str());
  FUZZ_CHECK((*again)->sameTables(c), "tables changed");
  FUZZ_CHECK((*again)->mixtures().size() == c.mixtures().size(), "mixtures changed");
  return 0;
}
