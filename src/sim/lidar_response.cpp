#include "lidar_response.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {
namespace {

double uniformOf(uint64_t key, uint64_t purpose) { return unitFromHash(splitMix64(key ^ purpose)); }
/// Standard normal quantiles at (i + 0.5) / 4096 (tails cut at 3.5 sigma), by bisection on erf.
const std::array<float, 4096>& normalTable() {
  static const std::array<float, 4096> kTable = [] {
    std::array<float, 4096> t{};
    for (int i = 0; i < 4096; ++i) {
      const double p = (i + 0.5) / 4096.0;
      double lo = -6.0, hi = 6.0;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
      }
      t[i] = static_cast<float>(0.5 * (lo + hi));
    }
    return t;
  }();
  return kTable;
}

/// Two independent standard normals from one hash (table lookups: no transcendental calls).
void normalPair(uint64_t key, uint64_t purpose, double* a, double* b) {
  const uint64_t h = splitMix64(key ^ purpose);
  const auto& table = normalTable();
  *a = table[h >> 52];
  *b = table[(h >> 40) & 4095u];
}

}  // namespace

Return lidarResponse(const Hdl32eConfig& c, uint64_t key, Material m, float range_m,
                     float cos_incidence) {
  const MaterialResponse& mr = materialResponse(m);
  // Received power ~ rho cos(theta) / r^2; detection probability is a logistic in log power,
  // 1/2 at the threshold.
  const double ref = c.detection_reference_m / std::max(0.5f, range_m);
  const double power = mr.reflectivity * std::max(0.02f, cos_incidence) * ref * ref;
  double p_detect = 1.0;
  if (c.detection_threshold > 0.0) {
    const double q = c.detection_threshold / power;  // logistic in log power, slope 2.5
    p_detect = 1.0 / (1.0 + q * q * std::sqrt(q));
  }
  p_detect *= (1.0 - mr.extra_dropout) * (1.0 - c.dropout_probability);
  Return r{false, range_m, 0.0f};
  if (uniformOf(key, 0x11) >= p_detect) return r;
  r.detected = true;
  double n_range, n_intensity;
  normalPair(key, 0x22, &n_range, &n_intensity);
  r.range_m = static_cast<float>(range_m + c.range_noise_m * n_range);
  // Velodyne intensities are calibrated reflectivities: rho x (Lambertian-ish incidence term),
  // with +-8% texture and additive noise.
  double i = 255.0 * mr.reflectivity * (0.35 + 0.65 * cos_incidence) *
             (0.92 + 0.16 * uniformOf(key, 0x33));
  if (m == Material::kSign || m == Material::kLaneMarking)
    i = std::max(i, 255.0 * mr.reflectivity * 0.9);
  i += c.intensity_noise * n_intensity;
  r.intensity = static_cast<float>(std::round(std::clamp(i, 0.0, 255.0)));
  return r;
}

Return flakeResponse(const Hdl32eConfig& c, uint64_t key, float range_m) {
  double n_range, unused;
  normalPair(key, 0x55, &n_range, &unused);
  Return r{true, static_cast<float>(range_m + c.range_noise_m * n_range), 0.0f};
  r.intensity =
      static_cast<float>(std::round(std::clamp(3.0 + 12.0 * uniformOf(key, 0x66), 0.0, 255.0)));
  return r;
}

}  // namespace sim
}  // namespace gmm_localization
