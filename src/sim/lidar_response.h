#pragma once
// Private: the per-return sensor response (detection, range noise, intensity).

#include <cstdint>

#include "gmm_localization/sim/hdl32e.h"
#include "gmm_localization/sim/materials.h"

namespace gmm_localization {
namespace sim {

struct Return {
  bool detected;
  float range_m;
  float intensity;
};

/// `key`: the ray's noise key; `cos_incidence` in [0, 1].
Return lidarResponse(const Hdl32eConfig& c, uint64_t key, Material m, float range_m,
                     float cos_incidence);

/// A return from a falling flake at `range_m` (small, weak target).
Return flakeResponse(const Hdl32eConfig& c, uint64_t key, float range_m);

}  // namespace sim
}  // namespace gmm_localization
