#pragma once
// On-disk format of a Gaussian mixture map: a directory with one manifest and one file per tile.
// All integers and floats are little-endian, written byte by byte (never a struct memcpy), so
// files are portable across compilers and architectures. Every file ends with a CRC-32 (zlib
// polynomial) of all bytes before it, and the manifest also records each tile file's size and
// CRC-32 so a swapped or stale tile is caught too.
//
// Tile file `tile_<tx>_<ty>.gmt`, format version 1:
//   off size field
//     0   4  magic "GMMT"
//     4   2  u16 format version (1)
//     6   2  u16 flags: bit 0 = payload is zlib-deflated; other bits must be 0
//     8   4  i32 tile x index            12  4  i32 tile y index
//    16   4  u32 tile size S [cells]     20  4  u32 total number of components in the tile
//    24   8  f64 base height b [m]       32  8  f64 mean quantum q [m]
//    40   4  u32 raw payload bytes       44  4  u32 stored payload bytes (= raw when not deflated)
//    48   -  stored payload
//   end   4  u32 CRC-32 of bytes [0, end)
// Raw payload (cells in row-major order, y outer, as GmmTile):
//   A. component count K of every cell, 2 bits each, 4 cells per byte, first cell in the low bits;
//   B. mean codes, slot-major: for j = 0..2, the j-th component of every cell with K > j; each
//      code is a u16 delta (mod 2^16) from the previous code of the same slot (first: from 0),
//      written as a plane of low bytes followed by a plane of high bytes (deflate-friendly);
//   C. sigma codes, same layout as B (also delta-coded);
//   D. weight codes, same slots but only for cells with K >= 2 (one component: weight 1), raw
//      codes (no delta), low-byte plane then high-byte plane.
// Quantisation (version 1), chosen so every reconstruction error stays far below a LIDAR's
// ~2 cm range noise:
//   mean   mu = b + code * q, b = the tile's smallest mean, q = max(1 mm, span / 65535):
//          error <= q / 2, i.e. <= 0.5 mm for tiles whose means span <= 65 m.
//   sigma  ln(sigma) uniform in [ln 1e-4 m, ln 1e4 m] over 65535 steps: relative error
//          <= 1.41e-4 (0.004 mm at 3 cm, 0.4 mm at 3 m). Out of range: the encoder fails.
//   weight ln(w) uniform in [ln 2^-20, 0] over 65535 steps, then the cell's weights are
//          renormalised to sum 1: relative error <= 2.2e-4. w < 2^-20: the encoder fails.
//
// Manifest `manifest.gmm`, format version 3 (versions 1 and 2 are still read):
//   magic "GMMM", u16 version, u16 flags (0); geometry: f64 resolution [m], u32 tile size
//   [cells], f64 origin x [m], f64 origin y [m]; georeference (georeference.h): u8 present,
//   string datum, [version >= 2: u8 UTM zone 0..60 (0: text only), u8 north 0/1,] f64
//   easting, northing, up of the map origin [m]; string provenance; [version >= 3: the layer
//   (reflectivity_layer.h): u8 layer, 0 height or 1 reflectivity; for reflectivity only, its
//   definition: f64 metres per intensity unit, f64 ground height, f64 ground band min, f64
//   ground band max [m], f64 ground range [m] (checkReflectivityLayer's bounds);] u32 tile
//   count, then per tile: i32 x, i32 y, string file name, u64 byte size, u32 tile CRC-32, f32
//   z min, f32 z max [m], 4 x u32 cells with 0..3 components; u32 CRC-32. Strings: u32 length
//   + bytes. A version 1 manifest's zone is taken from its datum text when that names one
//   (zoneFromDatumText); manifests before version 3 are height maps. Writers always write
//   version 3. In a reflectivity map every "z" and "height" of the tiles below (means, z
//   ranges) is the value intensity x metres per unit instead [m].
//
// Failure behaviour: decoders and readers return a failure whose reason names the file and the
// problem (missing, truncated, CRC mismatch, wrong magic, unsupported version, inconsistent
// sizes, invalid value). They never crash and never return a partly decoded map.
//
// Physical bounds (checked by the readers on top of the CRC, so that a CRC-correct but absurd
// file cannot make the map server or the rasterizer do unbounded work): resolution in
// [kMinMapResolutionM, kMaxMapResolutionM]; origin within kMaxMapOriginM of the frame's origin;
// every tile within kMaxMapExtentM of the map origin; every component mean within
// kMaxMapHeightM of z = 0, sigma in (0, kMaxComponentSigmaM], weight finite in (0, 1]; a
// manifest's tile z range within kMaxMapHeightM + 4 kMaxComponentSigmaM. Maps built by
// build_map (0.2 m cells, real-world heights) are far inside all of them.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/georeference.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/map/reflectivity_layer.h"

namespace gmm_localization {

constexpr uint16_t kTileFormatVersion = 1;      ///< tile files written and read
constexpr uint16_t kManifestFormatVersion = 3;  ///< manifests written
constexpr uint16_t kOldestManifestVersion = 1;  ///< oldest manifest still read
constexpr const char* kManifestFileName = "manifest.gmm";

constexpr double kMinMapResolutionM = 0.05;  ///< smallest accepted cell edge [m]
constexpr double kMaxMapResolutionM = 10.0;  ///< largest accepted cell edge [m]
constexpr double kMaxMapOriginM = 1e8;       ///< bound on |origin_x_m|, |origin_y_m| [m]
constexpr double kMaxMapExtentM = 1e6;       ///< bound on a tile's distance from the origin [m]
constexpr double kMaxMapHeightM = 1e4;       ///< bound on |component mean| [m]
constexpr double kMaxComponentSigmaM = 1e3;  ///< bound on a component's sigma [m]

/// Empty when `g` passes MapGeometry::validate() and the physical bounds above (resolution,
/// origin), else which field is wrong and why.
std::string checkMapGeometryBounds(const MapGeometry& g);
/// Empty when tile `id` of `g` lies within kMaxMapExtentM of the map origin (so cell and chunk
/// indices, and the number of chunks between any two tiles, stay bounded), else why.
std::string checkTileExtent(const MapGeometry& g, const TileId& id);
/// Empty when a component is within the physical bounds above, else which field is wrong.
std::string checkComponentBounds(const GaussianComponent& c);

/// The manifest's entry for one tile file.
struct TileInfo {
  TileId id;
  std::string file_name;   ///< relative to the map directory, no path separators
  uint64_t byte_size = 0;  ///< size of the tile file [bytes]
  uint32_t crc32 = 0;      ///< CRC-32 of the tile file without its 4-byte trailer (= the trailer)
  /// Height range that holds the tile's mass: min over components of mean - 4 sigma and max of
  /// mean + 4 sigma [m] (from the stored, quantised values). 0, 0 for a tile without components.
  float z_min_m = 0.f;
  float z_max_m = 0.f;
  /// cells_by_components[k]: number of cells with exactly k components; sums to S^2.
  std::array<uint32_t, kMaxMixtureComponents + 1> cells_by_components{};
};

struct MapManifest {
  uint16_t format_version = kManifestFormatVersion;  ///< as read (written: always the newest)
  MapGeometry geometry;
  Georeference georeference;
  std::string provenance;  ///< free text: tool, inputs and options that built the map
  /// What the cells hold: heights, or the values of the ground returns' intensities (read as
  /// kHeight from manifests before version 3).
  MapLayer layer = MapLayer::kHeight;
  /// The reflectivity layer's definition the map was built with (layer kReflectivity only; a
  /// matcher checks that it selects and scales its ground returns alike). ground_height_m is
  /// in the vehicle frame of the build's input (see PointBatch::vehicle_origin_m).
  ReflectivityLayerOptions reflectivity;
  std::vector<TileInfo> tiles;
};

/// A tile's file bytes and its manifest entry (file name, size, CRC, z range, counts).
struct EncodedTile {
  std::vector<uint8_t> bytes;
  TileInfo info;
};

struct TileCodecOptions {
  bool deflate = true;  ///< zlib-deflate the payload when that makes it smaller
  int deflate_level = 6;
};

/// CRC-32 (zlib) of a byte range.
uint32_t crc32Of(const uint8_t* data, size_t size);

/// "tile_<tx>_<ty>.gmt"
std::string tileFileName(const TileId& id);

/// The manifest entry's z range and component counts of a tile (file fields left empty).
TileInfo summarizeTile(const GmmTile& tile);

/// Encodes a tile. Fails (naming the cell) on a non-finite mean or one beyond kMaxMapHeightM, a
/// sigma outside [1e-4, kMaxComponentSigmaM] m, a weight outside [2^-20, 1], or a tile size
/// outside [8, 4096].
Result<EncodedTile> encodeTile(const GmmTile& tile, const TileCodecOptions& options = {});

/// Decodes tile bytes; `source` names the file in error messages. When `expected` is non-null
/// the tile's id and size must match it (tile_size_cells), else it fails. Fails, naming the
/// tile, the cell and the field, on a decoded component outside the physical bounds above.
Result<std::shared_ptr<GmmTile>> decodeTile(const uint8_t* data, size_t size,
                                            const std::string& source,
                                            const TileId* expected_id = nullptr,
                                            int32_t expected_size_cells = 0);

std::vector<uint8_t> encodeManifest(const MapManifest& manifest);
Result<MapManifest> decodeManifest(const uint8_t* data, size_t size, const std::string& source);

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, fsync, rename,
/// fsync of the directory. On any failure the temporary file is removed and an existing file at
/// `path` is left untouched.
Status writeFileAtomic(const std::string& path, const std::vector<uint8_t>& bytes);

/// Reads a whole file; fails for a missing or unreadable file or one larger than max_bytes.
Result<std::vector<uint8_t>> readFileBytes(const std::string& path,
                                           uint64_t max_bytes = (uint64_t{1} << 32));

/// Reads `<directory>/manifest.gmm`.
Result<MapManifest> readManifest(const std::string& directory);
/// Writes `<directory>/manifest.gmm` atomically.
Status writeManifest(const std::string& directory, const MapManifest& manifest);

/// Reads and decodes a tile file listed in a manifest: checks its size and CRC against `info`, then
/// decodes it expecting info.id and geometry.tile_size_cells.
Result<std::shared_ptr<GmmTile>> readTileFile(const std::string& directory, const TileInfo& info,
                                              const MapGeometry& geometry);

}  // namespace gmm_localization
