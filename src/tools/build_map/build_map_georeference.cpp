#include "build_map/build_map_georeference.h"

#include <cmath>
#include <cstdlib>
#include <utility>

namespace gmm_localization {
namespace tools {
namespace {

/// Records the zone one option names; fails when an earlier one named another.
std::string agree(std::optional<GridZone>& zone, const GridZone& z, const std::string& option) {
  if (zone && (zone->zone != z.zone || zone->north != z.north)) {
    return option + " names zone " + z.name() + " but another option names " + zone->name();
  }
  zone = z;
  return {};
}

}  // namespace

Result<Georeference> resolveGeoreference(const GeoreferenceArgs& a) {
  using R = Result<Georeference>;
  Georeference g;
  g.datum = a.datum;
  std::optional<GridZone> zone;
  for (const auto& [option, text] :
       {std::pair<std::string, std::string>{"--utm-zone", a.utm_zone}, {"--epsg", a.epsg}}) {
    if (text.empty()) continue;
    auto z = parseGridZone(text);
    if (!z) return R::failure(option + ": " + z.error());
    const std::string conflict = agree(zone, *z, option);
    if (!conflict.empty()) return R::failure(conflict);
  }
  const int origins =
      (a.offset_m ? 1 : 0) + (a.georef_origin_m ? 1 : 0) + (a.mgrs_origin.empty() ? 0 : 1);
  if (origins > 1) {
    return R::failure(
        "--offset, --georef-origin and --mgrs-origin each set the map origin: give one (--offset "
        "when the input is in grid coordinates, one of the others when it is already local)");
  }
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (a.offset_m) origin = *a.offset_m;
  if (a.georef_origin_m) origin = *a.georef_origin_m;
  if (!a.mgrs_origin.empty()) {
    std::string ref = a.mgrs_origin;
    double up = 0.0;
    const size_t comma = ref.find(',');
    if (comma != std::string::npos) {
      char* end = nullptr;
      const std::string up_text = ref.substr(comma + 1);
      up = std::strtod(up_text.c_str(), &end);
      if (up_text.empty() || *end != '\0' || !std::isfinite(up)) {
        return R::failure("--mgrs-origin: '" + up_text + "' after the comma is not a height [m]");
      }
      ref = ref.substr(0, comma);
    }
    auto m = parseMgrs(ref);
    if (!m) return R::failure("--mgrs-origin: " + m.error());
    const std::string conflict = agree(zone, m->zone, "--mgrs-origin");
    if (!conflict.empty()) return R::failure(conflict);
    origin = Eigen::Vector3d(m->easting_m, m->northing_m, up);
  }
  if (!origin.allFinite()) return R::failure("the map origin is not finite");
  if (!zone && !a.datum.empty()) {
    const GridZone z = zoneFromDatumText(a.datum);
    if (z.zone != 0) zone = z;
  }
  g.present = origins > 0 || zone.has_value() || !a.datum.empty();
  if (!g.present) return g;
  if (zone) {
    g.utm_zone = zone->zone;
    g.utm_north = zone->north;
    if (g.datum.empty()) g.datum = "WGS84 / UTM zone " + zone->name();
  }
  g.origin_easting_m = origin.x();
  g.origin_northing_m = origin.y();
  g.origin_up_m = origin.z();
  return g;
}

}  // namespace tools
}  // namespace gmm_localization
