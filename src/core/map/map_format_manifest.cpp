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

}  // namespace

std::vector<uint8_t> encodeManifest(const MapManifest& m) {
  std::vector<uint8_t> out;
  ByteWriter w(out);
  w.bytes(kManifestMagic, 4);
  w.u16(kMapFormatVersion);
  w.u16(0);
  w.f64(m.geometry.resolution_m);
  w.u32(static_cast<uint32_t>(m.geometry.tile_size_cells));
  w.f64(m.geometry.origin_x_m);
  w.f64(m.geometry.origin_y_m);
  w.u8(m.georeference.present ? 1 : 0);
  w.str(m.georeference.datum);
  w.f64(m.georeference.origin_easting_m);
  w.f64(m.georeference.origin_northing_m);
  w.f64(m.georeference.origin_up_m);
  w.str(m.provenance);
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
  if (size < 4) return fail("truncated: " + std::to_string(size) + " bytes, no room for the magic");
  if (!std::equal(data, data + 4, kManifestMagic))
    return fail("wrong magic (not a GMM map manifest)");
  ByteReader r(data, size);
  r.u32("magic");
  const uint16_t version = r.u16("format version");
  if (!r.ok()) return fail(r.error());
  if (version != kMapFormatVersion) {
    return fail("unsupported format version " + std::to_string(version) + " (this build reads " +
                std::to_string(kMapFormatVersion) + ")");
  }
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
  m.georeference.origin_easting_m = body.f64("origin easting");
  m.georeference.origin_northing_m = body.f64("origin northing");
  m.georeference.origin_up_m = body.f64("origin up");
  m.provenance = body.str("provenance", kMaxTextLength);
  const uint32_t n_tiles = body.u32("tile count");
  if (!body.ok()) return fail(body.error());
  if (flags != 0) return fail("unknown flags " + std::to_string(flags));
  const std::string geometry_error = m.geometry.validate();
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
    if (!std::isfinite(t.z_min_m) || !std::isfinite(t.z_max_m) || t.z_min_m > t.z_max_m) {
      return fail(which + ": invalid z range");
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
