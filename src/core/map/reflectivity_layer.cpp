// The reflectivity layer's bounds and description (definitions in reflectivity_layer.h).
#include "gmm_localization/core/map/reflectivity_layer.h"

#include <sstream>

namespace gmm_localization {
namespace {

/// "name=value must be in range" when v is not within [lo, hi] (lo excluded when open_lo).
std::string outside(const char* name, double v, double lo, double hi, bool open_lo) {
  if (std::isfinite(v) && (open_lo ? v > lo : v >= lo) && v <= hi) return {};
  std::ostringstream s;
  s << name << "=" << v << " must be in " << (open_lo ? "(" : "[") << lo << ", " << hi << "]";
  return s.str();
}

}  // namespace

std::string checkReflectivityLayer(const ReflectivityLayerOptions& o) {
  // Wide enough for any sensor's intensity scale (0..1 floats want ~5 m per unit, 16-bit
  // returns ~0.002), tight enough that every value stays far inside the map format's heights.
  for (const std::string& e : {outside("metres_per_unit", o.metres_per_unit, 0.0, 100.0, true),
                               outside("ground_height_m", o.ground_height_m, -100.0, 100.0, false),
                               outside("ground_min_m", o.ground_min_m, -10.0, 10.0, false),
                               outside("ground_max_m", o.ground_max_m, -10.0, 10.0, false),
                               outside("max_range_m", o.max_range_m, 0.0, 1000.0, true)}) {
    if (!e.empty()) return e;
  }
  if (!(o.ground_min_m < o.ground_max_m)) {
    std::ostringstream s;
    s << "ground_max_m=" << o.ground_max_m << " must exceed ground_min_m=" << o.ground_min_m;
    return s.str();
  }
  return {};
}

std::string describeReflectivityLayer(const ReflectivityLayerOptions& o) {
  std::ostringstream s;
  s << "value = intensity x " << o.metres_per_unit << " m; ground: [" << o.ground_min_m << ", "
    << o.ground_max_m << "] m around z = " << o.ground_height_m
    << " m of the vehicle frame, within " << o.max_range_m << " m";
  return s.str();
}

}  // namespace gmm_localization
