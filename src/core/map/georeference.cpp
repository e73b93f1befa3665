// Georeference: zone texts, MGRS and the geodetic <-> map conversions (GeographicLib's UTM).
#include "gmm_localization/core/map/georeference.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <regex>

#include <GeographicLib/MGRS.hpp>
#include <GeographicLib/UTMUPS.hpp>

namespace gmm_localization {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// The zone of an EPSG code 326zz / 327zz, zone 0 otherwise.
GridZone zoneFromEpsg(long code) {
  if (code >= 32601 && code <= 32660) return GridZone{static_cast<int>(code - 32600), true};
  if (code >= 32701 && code <= 32760) return GridZone{static_cast<int>(code - 32700), false};
  return GridZone{0, true};
}

/// Finds a zone in free text: "EPSG:32617", a bare 326zz/327zz, or "<zz><N|S>" after "UTM" or
/// alone. Zone 0 when none.
GridZone findZone(const std::string& text, bool require_whole) {
  const std::string t = upper(text);
  std::smatch m;
  const std::regex epsg(require_whole ? R"(^\s*(?:EPSG\s*:\s*)?(32[67]\d\d)\s*$)"
                                      : R"((?:EPSG\s*:\s*)(32[67]\d\d))");
  if (std::regex_search(t, m, epsg))
    return zoneFromEpsg(std::strtol(m[1].str().c_str(), nullptr, 10));
  const std::regex utm(
      require_whole ? R"(^\s*(?:WGS\s*84\s*/\s*)?(?:UTM\s*(?:ZONE\s*)?)?(\d{1,2})\s*([NS])\s*$)"
                    : R"(UTM\s*(?:ZONE\s*)?(\d{1,2})\s*([NS])\b)");
  if (std::regex_search(t, m, utm)) {
    const int zone = std::atoi(m[1].str().c_str());
    if (zone >= 1 && zone <= 60) return GridZone{zone, m[2].str() == "N"};
  }
  return GridZone{0, true};
}

bool finite(double v) { return std::isfinite(v); }

}  // namespace

std::string GridZone::name() const { return std::to_string(zone) + (north ? "N" : "S"); }

std::string Georeference::describe() const {
  if (!present) return "none";
  char origin[160];
  std::snprintf(origin, sizeof origin, "origin E %.3f N %.3f U %.3f m", origin_easting_m,
                origin_northing_m, origin_up_m);
  std::string s;
  if (hasGrid()) {
    s = "UTM " + grid().name() + " (EPSG:" + std::to_string(grid().epsg()) + "), " + origin;
  } else {
    s = std::string("no grid zone (text only), ") + origin;
  }
  if (!datum.empty()) s += ", '" + datum + "'";
  return s;
}

Result<GridZone> parseGridZone(const std::string& text) {
  const GridZone z = findZone(text, /*require_whole=*/true);
  if (z.zone == 0) {
    return Result<GridZone>::failure(
        "'" + text +
        "' names no WGS84 UTM zone (give e.g. 17N, 33S, \"WGS84 / UTM zone 17N\", EPSG:32617)");
  }
  return z;
}

GridZone zoneFromDatumText(const std::string& datum) {
  return findZone(datum, /*require_whole=*/false);
}

Result<MgrsPoint> parseMgrs(const std::string& text) {
  using R = Result<MgrsPoint>;
  std::string compact;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) compact += c;
  }
  int zone = 0, precision = 0;
  bool north = true;
  double x = 0.0, y = 0.0;
  try {
    GeographicLib::MGRS::Reverse(compact, zone, north, x, y, precision, /*centerp=*/false);
  } catch (const std::exception& e) {
    return R::failure("'" + text + "' is not an MGRS reference: " + e.what());
  }
  if (zone < 1 || zone > 60 || !finite(x) || !finite(y)) {
    return R::failure("'" + text + "' is a polar (UPS) or invalid MGRS reference: only UTM zones");
  }
  return MgrsPoint{GridZone{zone, north}, x, y};
}

Result<MapPosition> geodeticToMap(const Georeference& geo, const GeodeticPosition& p,
                                  double max_distance_m) {
  using R = Result<MapPosition>;
  if (!geo.hasGrid()) return R::failure("the map has no georeference with a UTM zone");
  if (!(finite(p.latitude_deg) && finite(p.longitude_deg) && finite(p.altitude_m)) ||
      std::abs(p.latitude_deg) > 84.0 || std::abs(p.longitude_deg) > 180.0) {
    return R::failure("position not finite or outside UTM's latitudes (+-84 deg)");
  }
  int zone = 0;
  bool north = true;
  double x = 0.0, y = 0.0, gamma_deg = 0.0, k = 0.0;
  try {
    GeographicLib::UTMUPS::Forward(p.latitude_deg, p.longitude_deg, zone, north, x, y, gamma_deg, k,
                                   geo.utm_zone);
  } catch (const std::exception& e) {
    return R::failure(std::string("UTM conversion failed: ") + e.what());
  }
  // Forward gives the hemisphere of the point; the map's may differ near the equator: UTM south
  // northings are offset by 10000 km.
  if (north != geo.utm_north) y += geo.utm_north ? -1e7 : 1e7;
  MapPosition out;
  out.x_m = x - geo.origin_easting_m;
  out.y_m = y - geo.origin_northing_m;
  out.z_m = p.altitude_m - geo.origin_up_m;
  out.convergence_rad = gamma_deg * kDegToRad;
  if (!(std::hypot(out.x_m, out.y_m) <= max_distance_m)) {
    char why[160];
    std::snprintf(why, sizeof why, "position is %.0f m from the map origin (more than %.0f m)",
                  std::hypot(out.x_m, out.y_m), max_distance_m);
    return R::failure(why);
  }
  return out;
}

Result<GeodeticPosition> mapToGeodetic(const Georeference& geo, double x_m, double y_m,
                                       double z_m) {
  using R = Result<GeodeticPosition>;
  if (!geo.hasGrid()) return R::failure("the map has no georeference with a UTM zone");
  if (!(finite(x_m) && finite(y_m) && finite(z_m))) return R::failure("position not finite");
  GeodeticPosition out;
  double gamma = 0.0, k = 0.0;
  try {
    GeographicLib::UTMUPS::Reverse(geo.utm_zone, geo.utm_north, x_m + geo.origin_easting_m,
                                   y_m + geo.origin_northing_m, out.latitude_deg, out.longitude_deg,
                                   gamma, k);
  } catch (const std::exception& e) {
    return R::failure(std::string("UTM conversion failed: ") + e.what());
  }
  out.altitude_m = z_m + geo.origin_up_m;
  return out;
}

}  // namespace gmm_localization
