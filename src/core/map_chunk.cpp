#include "gmm_localization/core/map_chunk.h"

namespace gmm_localization {

size_t MapChunk::bytes() const {
  size_t total = mixtures_.size() * (sizeof(GaussianMixture1D) + sizeof(MixtureLogTerms));
  const size_t plane = static_cast<size_t>(cells()) * static_cast<size_t>(cells());
  for (const RasterLayer& L : layers_) total += static_cast<size_t>(L.nz) * plane;
  return total;
}

}  // namespace gmm_localization
