// The manifest's versions (map_format.h): version 3 records the map's layer and the
// reflectivity layer's definition; versions 1 and 2 still load, as height maps. The manifests
// are written here from the documented layout, field by field, independently of the encoder.
#include <cmath>
#include <cstring>
#include <fstream>

#include <gtest/gtest.h>

#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/core/map/map_store.h"
#include "support/temp_dir.h"

namespace gmm_localization {
namespace {

using testing::TempDir;

/// Little-endian fields, as map_format.h documents them.
struct SpecWriter {
  std::vector<uint8_t> b;
  void bytes(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void f64(double v) {
    uint64_t u;
    std::memcpy(&u, &v, 8);
    bytes(u, 8);
  }
  void f32(float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    bytes(u, 4);
  }
  void str(const std::string& s) {
    bytes(s.size(), 4);
    b.insert(b.end(), s.begin(), s.end());
  }
};

/// `m` as a manifest of format `version` (1, 2 or 3), following the documented layout.
std::vector<uint8_t> specManifest(const MapManifest& m, uint16_t version) {
  SpecWriter w;
  w.b = {'G', 'M', 'M', 'M'};
  w.bytes(version, 2);
  w.bytes(0, 2);
  w.f64(m.geometry.resolution_m);
  w.bytes(m.geometry.tile_size_cells, 4);
  w.f64(m.geometry.origin_x_m);
  w.f64(m.geometry.origin_y_m);
  w.bytes(m.georeference.present ? 1 : 0, 1);
  w.str(m.georeference.datum);
  if (version >= 2) {
    w.bytes(m.georeference.utm_zone, 1);
    w.bytes(m.georeference.utm_north ? 1 : 0, 1);
  }
  w.f64(m.georeference.origin_easting_m);
  w.f64(m.georeference.origin_northing_m);
  w.f64(m.georeference.origin_up_m);
  w.str(m.provenance);
  if (version >= 3) {
    w.bytes(static_cast<uint8_t>(m.layer), 1);
    if (m.layer == MapLayer::kReflectivity) {
      w.f64(m.reflectivity.metres_per_unit);
      w.f64(m.reflectivity.ground_height_m);
      w.f64(m.reflectivity.ground_min_m);
      w.f64(m.reflectivity.ground_max_m);
      w.f64(m.reflectivity.max_range_m);
    }
  }
  w.bytes(m.tiles.size(), 4);
  for (const TileInfo& t : m.tiles) {
    w.bytes(static_cast<uint32_t>(t.id.x), 4);
    w.bytes(static_cast<uint32_t>(t.id.y), 4);
    w.str(t.file_name);
    w.bytes(t.byte_size, 8);
    w.bytes(t.crc32, 4);
    w.f32(t.z_min_m);
    w.f32(t.z_max_m);
    for (uint32_t c : t.cells_by_components) w.bytes(c, 4);
  }
  w.bytes(crc32Of(w.b.data(), w.b.size()), 4);
  return w.b;
}

MapManifest sample(MapLayer layer) {
  MapManifest m;
  m.geometry.tile_size_cells = 16;
  m.geometry.origin_x_m = -3.5;
  m.georeference.present = true;
  m.georeference.datum = "WGS84 / UTM zone 17N";
  m.georeference.utm_zone = 17;
  m.georeference.origin_easting_m = 277000.0;
  m.georeference.origin_northing_m = 4686000.0;
  m.provenance = "manifest_versions_test";
  m.layer = layer;
  m.reflectivity.metres_per_unit = 0.025;
  m.reflectivity.ground_height_m = -1.73;
  m.reflectivity.ground_min_m = -0.2;
  m.reflectivity.ground_max_m = 0.25;
  m.reflectivity.max_range_m = 35.0;
  for (int i = 0; i < 2; ++i) {
    TileInfo t;
    t.id = {i, -1};
    t.file_name = tileFileName(t.id);
    t.byte_size = 900 + i;
    t.crc32 = 0x1234 + i;
    t.z_min_m = 0.1f;
    t.z_max_m = 2.5f;
    t.cells_by_components = {200, 50, 6, 0};
    m.tiles.push_back(t);
  }
  return m;
}

TEST(ManifestVersions, EncoderWritesTheDocumentedVersion3Layout) {
  EXPECT_EQ(kManifestFormatVersion, 3);
  for (MapLayer layer : {MapLayer::kHeight, MapLayer::kReflectivity}) {
    const MapManifest m = sample(layer);
    EXPECT_TRUE(encodeManifest(m) == specManifest(m, 3)) << mapLayerName(layer);
  }
  // A height map's version 3 manifest is its version 2 one plus the layer byte.
  const MapManifest h = sample(MapLayer::kHeight);
  EXPECT_EQ(encodeManifest(h).size(), specManifest(h, 2).size() + 1);
}

TEST(ManifestVersions, ReflectivityLayerRoundTrips) {
  const MapManifest m = sample(MapLayer::kReflectivity);
  const auto bytes = encodeManifest(m);
  auto r = decodeManifest(bytes.data(), bytes.size(), "m.gmm");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->format_version, 3);
  EXPECT_EQ(r->layer, MapLayer::kReflectivity);
  EXPECT_EQ(r->reflectivity.metres_per_unit, 0.025);
  EXPECT_EQ(r->reflectivity.ground_height_m, -1.73);
  EXPECT_EQ(r->reflectivity.ground_min_m, -0.2);
  EXPECT_EQ(r->reflectivity.ground_max_m, 0.25);
  EXPECT_EQ(r->reflectivity.max_range_m, 35.0);
  ASSERT_EQ(r->tiles.size(), 2u);
  EXPECT_EQ(r->tiles[1].crc32, 0x1235u);
  for (size_t n = 0; n < bytes.size(); ++n) {
    ASSERT_FALSE(decodeManifest(bytes.data(), n, "m.gmm").ok()) << "prefix " << n;
  }
  for (size_t bit = 0; bit < bytes.size() * 8; ++bit) {
    auto c = bytes;
    c[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    ASSERT_FALSE(decodeManifest(c.data(), c.size(), "m.gmm").ok()) << "bit " << bit;
  }
}

TEST(ManifestVersions, Versions1And2LoadAsHeightMaps) {
  // Whatever the struct says, an old manifest has no layer: it is a height map.
  const MapManifest m = sample(MapLayer::kReflectivity);
  for (uint16_t version : {1, 2}) {
    const auto bytes = specManifest(m, version);
    auto r = decodeManifest(bytes.data(), bytes.size(), "old.gmm");
    ASSERT_TRUE(r.ok()) << "version " << version << ": " << r.error();
    EXPECT_EQ(r->format_version, version);
    EXPECT_EQ(r->layer, MapLayer::kHeight);
    EXPECT_EQ(r->georeference.utm_zone, 17) << "version 1: from the datum text";
    EXPECT_EQ(r->provenance, "manifest_versions_test");
    ASSERT_EQ(r->tiles.size(), 2u);
    EXPECT_EQ(r->tiles[0].file_name, "tile_0_-1.gmt");
    EXPECT_EQ(r->tiles[1].cells_by_components[2], 6u);
    // Re-encoded, it is a version 3 height map.
    const auto again = encodeManifest(*r);
    EXPECT_EQ(again[4], 3);
    EXPECT_EQ(decodeManifest(again.data(), again.size(), "new.gmm")->layer, MapLayer::kHeight);
  }
  // MapStore says so too.
  TempDir dir("gmm_manifest_versions");
  const auto v2 = specManifest(m, 2);
  std::ofstream(dir.path + "/" + kManifestFileName, std::ios::binary)
      .write(reinterpret_cast<const char*>(v2.data()), static_cast<std::streamsize>(v2.size()));
  auto store = MapStore::open(dir.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->manifest().format_version, 2);
  EXPECT_EQ(store->layer(), MapLayer::kHeight);
}

TEST(ManifestVersions, UnknownLayersAndAbsurdDefinitionsAreRefused) {
  auto decodeError = [](const MapManifest& m) {
    const auto bytes = specManifest(m, 3);
    auto r = decodeManifest(bytes.data(), bytes.size(), "bad.gmm");
    return r.ok() ? std::string("accepted") : r.error();
  };
  MapManifest m = sample(MapLayer::kHeight);
  m.layer = static_cast<MapLayer>(2);
  EXPECT_EQ(decodeError(m), "manifest 'bad.gmm': unknown layer 2 (0 height, 1 reflectivity)");
  m = sample(MapLayer::kReflectivity);
  m.reflectivity.metres_per_unit = 0.0;
  EXPECT_NE(decodeError(m).find("invalid reflectivity layer: metres_per_unit=0 must be in"),
            std::string::npos)
      << decodeError(m);
  m = sample(MapLayer::kReflectivity);
  m.reflectivity.ground_min_m = NAN;
  EXPECT_NE(decodeError(m).find("ground_min_m=nan"), std::string::npos) << decodeError(m);
  m = sample(MapLayer::kReflectivity);
  m.reflectivity.ground_max_m = m.reflectivity.ground_min_m;
  EXPECT_NE(decodeError(m).find("ground_max_m=-0.2 must exceed ground_min_m=-0.2"),
            std::string::npos)
      << decodeError(m);
  m = sample(MapLayer::kReflectivity);
  m.reflectivity.max_range_m = -1.0;
  EXPECT_NE(decodeError(m).find("max_range_m=-1"), std::string::npos) << decodeError(m);
  EXPECT_EQ(decodeError(sample(MapLayer::kReflectivity)), "accepted");
}

}  // namespace
}  // namespace gmm_localization
