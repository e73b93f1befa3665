// Map format: the manifest codec (layout documented in map_format.h).
#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"
#include "map_format_bytes.h"

namespace gmm_localization {
namespace {

using map_format::ByteReader;
using map_format::ByteWriter;

constexpr uint8_t kManifestMagic[4] = {'G', 'M', 'M', 'M'};
constexpr uint32_t kMaxTiles = 1u << 22;
constexpr uint32_t kMaxFileNameLength = 255;
constexpr uint32_t kMaxTextLength = 1u << 20;

/// A tile file name must stay inside the map directory.
bool safeFileName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\0') == std::string::npos;
}

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::string checkMapGeometryBounds(const MapGeometry& g) {
  const std::string basic = g.validate();
  if (!basic.empty()) return basic;
  if (!(g.resolution_m >= kMinMapResolutionM && g.resolution_m <= kMaxMapResolutionM)) {
    return "resolution_m=" + num(g.resolution_m) + " outside the physical range [" +
           num(kMinMapResolutionM) + ", " + num(kMaxMapResolutionM) + "] m";
  }
  if (!(std::abs(g.origin_x_m) <= kMaxMapOriginM && std::abs(g.origin_y_m) <= kMaxMapOriginM)) {
    return "origin (" + num(g.origin_x_m) + ", " + num(g.origin_y_m) + ") m beyond " +
           num(kMaxMapOriginM) + " m";
  }
  return {};
}

std::string checkTileExtent(const MapGeometry& g, const TileId& id) {
  // The farther corner of the tile from the origin, in metres (exact in double).
  const double size_m = g.tileSizeM();
  const double fx = std::max(std::abs(double(id.x)), std::abs(double(id.x) + 1.0)) * size_m;
  const double fy = std::max(std::abs(double(id.y)), std::abs(double(id.y) + 1.0)) * size_m;
  if (!(fx <= kMaxMapExtentM && fy <= kMaxMapExtentM)) {
    return "tile (" + std::to_string(id.x) + ", " + std::to_string(id.y) + ") lies beyond " +
           num(kMaxMapExtentM) + " m of the map origin";
  }
  return {};
}

std::string checkComponentBounds(const GaussianComponent& c) {
  if (!(std::abs(c.mean_m) <= kMaxMapHeightM)) {
    return "mean " + num(c.mean_m) + " m beyond the physical height range +-" +
           num(kMaxMapHeightM) + " m";
  }
  if (!(c.sigma_m > 0.f && c.sigma_m <= kMaxComponentSigmaM)) {
    return "sigma " + num(c.sigma_m) + " m outside (0, " + num(kMaxComponentSigmaM) + "] m";
  }
  if (!(c.weight > 0.f && c.weight <= 1.f)) {
    return "weight " + num(c.weight) + " outside (0, 1]";
  }
  return {};
}

std::vector<uint8_t> encodeManifest(const MapManifest& m) {
  std::vector<uint8_t> out;
  ByteWriter w(out);
  w.bytes(kManifestMagic, 4);
  w.u16(kManifestFormatVersion);
  w.u16(0);
  w.f64(m.geometry.resolution_m);
  w.u32(static_cast<uint32_t>(m.geometry.tile_size_cells));
  w.f64(m.geometry.origin_x_m);
  w.f64(m.geometry.origin_y_m);
  w.u8(m.georeference.present ? 1 : 0);
  w.str(m.georeference.datum);
  w.u8(static_cast<uint8_t>(m.georeference.utm_zone));
  w.u8(m.georeference.utm_north ? 1 : 0);
  w.f64(m.georeference.origin_easting_m);
  w.f64(m.georeference.origin_northing_m);
  w.f64(m.georeference.origin_up_m);
  w.str(m.provenance);
  w.u8(static_cast<uint8_t>(m.layer));
  if (m.layer == MapLayer::kReflectivity) {
    const ReflectivityLayerOptions& r = m.reflectivity;
    w.f64(r.metres_per_unit);
    w.f64(r.ground_height_m);
    w.f64(r.ground_min_m);
    w.f64(r.ground_max_m);
    w.f64(r.max_range_m);
  }
  w.u32(static_cast<uint32_t>(m.tiles.size()));
  for (const TileInfo& t : m.tiles) {
    w.i32(t.id.x);
    w.i32(t.id.y);
    w.str(t.file_name);
    w.u64(t.byte_size);
    w.u32(t.crc32);
    w.f32(t.z_min_m);
    w.f32(t.z_max_m);
    for (uint32_t c : t.cells_by_components) w.u32(c);
  }
  w.u32(crc32Of(out.data(), out.size()));
  return out;
}

Result<MapManifest> decodeManifest(const uint8_t* data, size_t size, const std::string& source) {
  using R = Result<MapManifest>;
  auto fail = [&](const std::string& what) {
    return R::failure("manifest '" + source + "': " + what);
  };
  ByteReader r(data, size);
  uint16_t version = 0;
  const std::string start =
      map_format::readFileStart(r, data, size, kManifestMagic, "GMM map manifest",
                                kOldestManifestVersion, kManifestFormatVersion, &version);
  if (!start.empty()) return fail(start);
  if (size < 12) return fail("truncated: " + std::to_string(size) + " bytes");
  const uint32_t stored_crc = static_cast<uint32_t>(data[size - 4]) | (data[size - 3] << 8) |
                              (data[size - 2] << 16) |
                              (static_cast<uint32_t>(data[size - 1]) << 24);
  const uint32_t crc = crc32Of(data, size - 4);
  if (crc != stored_crc) {
    std::ostringstream s;
    s << "CRC-32 mismatch (stored 0x" << std::hex << stored_crc << ", computed 0x" << crc
      << "): the file is truncated or corrupted";
    return fail(s.str());
  }
  ByteReader body(data, size - 4);
  body.u32("magic");
  body.u16("format version");
  MapManifest m;
  m.format_version = version;
  const uint16_t flags = body.u16("flags");
  m.geometry.resolution_m = body.f64("resolution");
  m.geometry.tile_size_cells = static_cast<int32_t>(body.u32("tile size"));
  m.geometry.origin_x_m = body.f64("origin x");
  m.geometry.origin_y_m = body.f64("origin y");
  m.georeference.present = body.u8("georeference flag") != 0;
  m.georeference.datum = body.str("datum", kMaxTextLength);
  uint8_t zone = 0, north = 1;
  if (version >= 2) {
    zone = body.u8("UTM zone");
    north = body.u8("UTM hemisphere");
  } else {
    const GridZone z = zoneFromDatumText(m.georeference.datum);
    zone = static_cast<uint8_t>(z.zone);
    north = z.north ? 1 : 0;
  }
  m.georeference.origin_easting_m = body.f64("origin easting");
  m.georeference.origin_northing_m = body.f64("origin northing");
  m.georeference.origin_up_m = body.f64("origin up");
  m.provenance = body.str("provenance", kMaxTextLength);
  uint8_t layer = 0;  // before version 3: height maps
  if (version >= 3) {
    layer = body.u8("layer");
    if (layer == static_cast<uint8_t>(MapLayer::kReflectivity)) {
      ReflectivityLayerOptions& r = m.reflectivity;
      r.metres_per_unit = body.f64("metres per unit");
      r.ground_height_m = body.f64("ground height");
      r.ground_min_m = body.f64("ground band min");
      r.ground_max_m = body.f64("ground band max");
      r.max_range_m = body.f64("ground range");
    }
  }
  const uint32_t n_tiles = body.u32("tile count");
  if (!body.ok()) return fail(body.error());
  if (flags != 0) return fail("unknown flags " + std::to_string(flags));
  if (layer > static_cast<uint8_t>(MapLayer::kReflectivity)) {
    return fail("unknown layer " + std::to_string(layer) + " (0 height, 1 reflectivity)");
  }
  m.layer = static_cast<MapLayer>(layer);
  if (m.layer == MapLayer::kReflectivity) {
    const std::string layer_error = checkReflectivityLayer(m.reflectivity);
    if (!layer_error.empty()) return fail("invalid reflectivity layer: " + layer_error);
  }
  if (zone > 60 || north > 1) {
    return fail("invalid georeference: UTM zone " + std::to_string(zone) + ", hemisphere " +
                std::to_string(north) + " (zone 0..60, hemisphere 0 south / 1 north)");
  }
  m.georeference.utm_zone = zone;
  m.georeference.utm_north = north != 0;
  {
    const Georeference& g = m.georeference;
    if (g.present && !(std::isfinite(g.origin_easting_m) && std::isfinite(g.origin_northing_m) &&
                       std::isfinite(g.origin_up_m))) {
      return fail("invalid georeference: origin not finite");
    }
  }
  const std::string geometry_error = checkMapGeometryBounds(m.geometry);
  if (!geometry_error.empty()) return fail("invalid geometry: " + geometry_error);
  // Each tile entry takes at least 48 bytes: refuse a count the file cannot hold.
  if (n_tiles > kMaxTiles || uint64_t{n_tiles} * 48 > body.remaining()) {
    return fail("inconsistent sizes: " + std::to_string(n_tiles) + " tiles declared, " +
                std::to_string(body.remaining()) + " bytes left");
  }
  const uint64_t cells = uint64_t(m.geometry.tile_size_cells) * m.geometry.tile_size_cells;
  std::set<TileId> seen;
  m.tiles.resize(n_tiles);
  for (TileInfo& t : m.tiles) {
    t.id.x = body.i32("tile x");
    t.id.y = body.i32("tile y");
    t.file_name = body.str("tile file name", kMaxFileNameLength);
    t.byte_size = body.u64("tile byte size");
    t.crc32 = body.u32("tile CRC");
    t.z_min_m = body.f32("tile z min");
    t.z_max_m = body.f32("tile z max");
    uint64_t sum = 0;
    for (uint32_t& c : t.cells_by_components) sum += (c = body.u32("tile cell counts"));
    if (!body.ok()) return fail(body.error());
    const std::string which =
        "tile (" + std::to_string(t.id.x) + ", " + std::to_string(t.id.y) + ")";
    if (!safeFileName(t.file_name)) return fail(which + ": unsafe file name '" + t.file_name + "'");
    if (!seen.insert(t.id).second) return fail(which + " is listed twice");
    const std::string extent_error = checkTileExtent(m.geometry, t.id);
    if (!extent_error.empty()) return fail("invalid extent: " + extent_error);
    constexpr double kMaxZ = kMaxMapHeightM + 4.0 * kMaxComponentSigmaM;
    if (!std::isfinite(t.z_min_m) || !std::isfinite(t.z_max_m) || t.z_min_m > t.z_max_m) {
      return fail(which + ": invalid z range");
    }
    if (!(std::abs(t.z_min_m) <= kMaxZ && std::abs(t.z_max_m) <= kMaxZ)) {
      return fail(which + ": z range [" + num(t.z_min_m) + ", " + num(t.z_max_m) +
                  "] m beyond the physical height range +-" + num(kMaxZ) + " m");
    }
    if (sum != cells) {
      return fail("inconsistent sizes: " + which + " cell counts sum to " + std::to_string(sum) +
                  ", expected " + std::to_string(cells));
    }
  }
  if (body.remaining() != 0) {
    return fail("inconsistent sizes: " + std::to_string(body.remaining()) +
                " unexpected bytes after the tile list");
  }
  return m;
}

}  // namespace gmm_localization
