// build_map's command line for the map layer (--layer and the reflectivity layer's options):
// which inputs can feed which layer.
#include <utility>

#include "build_map/build_map_options.h"

namespace gmm_localization {
namespace tools {

std::string checkLayerArgs(const BuildMapConfig& c, const std::string& reflectivity_only) {
  const bool reflectivity = c.builder.layer == MapLayer::kReflectivity;
  if (!reflectivity_only.empty() && !reflectivity)
    return reflectivity_only + " applies to --layer reflectivity only";
  if (!reflectivity) return {};
  if (c.input == InputKind::kPcd) {
    // Ground returns are told by their height above the vehicle, and a point-cloud map has no
    // vehicle poses. A ground of its own (say the lowest surface around each cell) would define
    // ground unlike the matcher, which levels each scan around its own vehicle: refused.
    return "--layer reflectivity needs scans with poses (--kitti, --bag or --synthetic-street): "
           "a PCD map has no vehicle poses, so its ground returns cannot be selected as the "
           "matcher selects them (by their height above the vehicle)";
  }
  if (c.input == InputKind::kKitti && c.kitti.fields == KittiFields::kXyz) {
    return "--layer reflectivity needs intensities, and --kitti-fields xyz has none (x, y, z, "
           "intensity records: --kitti-fields xyzi)";
  }
  return {};
}

std::string withLayerOption(const std::string& error) {
  const std::pair<const char*, const char*> by_field[] = {
      {"reflectivity.metres_per_unit", "--reflectivity-scale"},
      {"reflectivity.ground_height_m", "--ground-height"},
      {"reflectivity.ground_min_m", "--ground-band"},
      {"reflectivity.ground_max_m", "--ground-band"},
      {"reflectivity.max_range_m", "--ground-range"}};
  for (const auto& [field, option] : by_field) {
    if (error.rfind(field, 0) == 0) return std::string(option) + ": " + error;
  }
  return error;
}

}  // namespace tools
}  // namespace gmm_localization
