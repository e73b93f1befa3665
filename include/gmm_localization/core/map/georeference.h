#pragma once
// The link from a map frame to the Earth: the UTM grid (WGS84) the map frame is a shifted copy of.
//
// Convention: the map frame's axes are the grid's (x = easting, y = northing, z = up) and its
// origin (0, 0, 0) sits at (origin_easting_m, origin_northing_m, origin_up_m) of UTM zone
// `utm_zone` in the hemisphere `utm_north`. origin_up_m is on the same height reference as the
// GNSS receiver's altitude (sensor_msgs/NavSatFix: above the WGS84 ellipsoid) unless the map's
// builder says otherwise in `datum`. A map point p is at grid coordinates p + origin.
//
// Grid north is not true north: at a point of longitude offset dl from the zone's central
// meridian the grid is turned by the meridian convergence gamma (about dl * sin(latitude), up to
// ~3 deg at a zone edge). A heading measured from true east (ENU yaw, REP-103/REP-145) becomes a
// map-frame yaw by adding gamma; geodeticToMap returns it.
//
// Accepted texts (parseGridZone): "17N", "17S", "UTM 17N", "WGS84 / UTM zone 17N", "EPSG:32617",
// "32617" (EPSG 326zz = WGS84 / UTM zone zz north, 327zz = south). An MGRS reference (e.g.
// "17TLG2772386245") gives a zone and a grid point at once (parseMgrs).

#include <cstdint>
#include <string>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {

/// A UTM zone of WGS84: 1..60 and the hemisphere.
struct GridZone {
  int zone = 0;  ///< 1..60
  bool north = true;
  /// EPSG code of "WGS 84 / UTM zone <zone><N|S>": 32600 + zone or 32700 + zone.
  uint32_t epsg() const { return (north ? 32600u : 32700u) + static_cast<uint32_t>(zone); }
  /// "17N"
  std::string name() const;
};

struct Georeference {
  bool present = false;
  /// Free text kept with the map (e.g. "WGS84 / UTM zone 17N, heights above the ellipsoid").
  std::string datum;
  /// 1..60 when the grid is known (the structured form); 0 when only `datum` text is given
  /// (maps built before the structured form, or a frame this build cannot name).
  int utm_zone = 0;
  bool utm_north = true;
  double origin_easting_m = 0.0;
  double origin_northing_m = 0.0;
  double origin_up_m = 0.0;

  /// True when the map can be placed on the Earth: present with a UTM zone.
  bool hasGrid() const { return present && utm_zone >= 1 && utm_zone <= 60; }
  GridZone grid() const { return GridZone{utm_zone, utm_north}; }
  /// One line for logs and map_info: "UTM 17N (EPSG:32617), origin E 277000.000 N ...".
  std::string describe() const;
};

/// Parses a zone text (forms in the header comment). Fails naming the text and the forms.
Result<GridZone> parseGridZone(const std::string& text);

/// An MGRS reference: its zone and the grid coordinates of the square's south-west corner
/// (to the reference's precision). Fails for an invalid reference or a polar (UPS) one.
struct MgrsPoint {
  GridZone zone;
  double easting_m = 0.0;
  double northing_m = 0.0;
};
Result<MgrsPoint> parseMgrs(const std::string& text);

/// Best effort for maps whose georeference is text only: the zone named in `datum` if it names
/// one (e.g. "WGS84 / UTM zone 17N", "EPSG:32617"), else zone 0.
GridZone zoneFromDatumText(const std::string& datum);

/// A geodetic position: WGS84 latitude and longitude [deg], altitude [m] (the receiver's).
struct GeodeticPosition {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double altitude_m = 0.0;
};

/// A geodetic position in a georeferenced map frame.
struct MapPosition {
  double x_m = 0.0, y_m = 0.0, z_m = 0.0;
  /// Meridian convergence at the point [rad]: map yaw = ENU yaw + convergence_rad.
  double convergence_rad = 0.0;
};

/// Converts into the map frame of `geo` (which must have a grid), forcing the map's zone even when
/// the point lies in a neighbouring one (UTM stays accurate a few hundred km past a zone edge).
/// Fails for a non-finite or out-of-range latitude/longitude, or a point farther than
/// max_distance_m from the map origin.
Result<MapPosition> geodeticToMap(const Georeference& geo, const GeodeticPosition& p,
                                  double max_distance_m = 1e5);

/// The inverse of geodeticToMap (altitude = z + origin_up_m).
Result<GeodeticPosition> mapToGeodetic(const Georeference& geo, double x_m, double y_m, double z_m);

}  // namespace gmm_localization
