#include "gmm_localization/core/raster/map_chunk.h"

#include <algorithm>

namespace gmm_localization {

size_t MapChunk::bytes() const {
  size_t total = mixtures_.size() * (sizeof(GaussianMixture1D) + sizeof(MixtureLogTerms));
  const size_t span_bytes = (2 * static_cast<size_t>(cells()) * cells() + 2) * sizeof(uint32_t);
  for (const RasterLayer& L : layers_) total += span_bytes + L.value_count;
  return total;
}

bool MapChunk::sameTables(const MapChunk& o) const {
  if (id_ != o.id_ || shift_ != o.shift_ || layers_.size() != o.layers_.size()) return false;
  const size_t n_spans = 2 * static_cast<size_t>(cells()) * cells() + 2;
  for (size_t k = 0; k < layers_.size(); ++k) {
    const RasterLayer& a = layers_[k];
    const RasterLayer& b = o.layers_[k];
    if (a.z_shift != b.z_shift || a.value_count != b.value_count ||
        !std::equal(a.spans, a.spans + n_spans, b.spans) ||
        !std::equal(a.values, a.values + a.value_count, b.values)) {
      return false;
    }
  }
  return true;
}

}  // namespace gmm_localization
