#include "gmm_localization/core/map/map_format.h"
#include "support/temp_dir.h"

#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;

using testing::TempDir;

GmmTile randomTile(TileId id, int size, uint32_t seed) {
  GmmTile t(id, size);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> k(0, kMaxMixtureComponents);
  std::uniform_real_distribution<double> mu(-5.0, 40.0), log_sigma(std::log(0.03), std::log(5.0)),
      w(0.02, 1.0);
  for (auto& cell : t.cells()) {
    const int n = k(rng);
    std::vector<double> ws(n);
    double sum = 0.0;
    for (auto& x : ws) sum += x = w(rng);
    for (int j = 0; j < n; ++j) {
      cell.add({static_cast<float>(ws[j] / sum), static_cast<float>(mu(rng)),
                static_cast<float>(std::exp(log_sigma(rng)))});
    }
  }
  return t;
}

void expectClose(const GmmTile& a, const GmmTile& b, double mean_tol) {
  ASSERT_EQ(a.sizeCells(), b.sizeCells());
  ASSERT_EQ(a.id(), b.id());
  double worst_ll = 0.0;
  for (size_t i = 0; i < a.cells().size(); ++i) {
    const auto& x = a.cells()[i];
    const auto& y = b.cells()[i];
    ASSERT_EQ(x.size(), y.size()) << "cell " << i;
    for (int j = 0; j < x.size(); ++j) {
      const auto& c = x.component(j);
      const auto& d = y.component(j);
      EXPECT_NEAR(d.mean_m, c.mean_m, mean_tol) << "cell " << i;
      EXPECT_NEAR(d.sigma_m / c.sigma_m, 1.0, 1.5e-4) << "cell " << i;
      EXPECT_NEAR(d.weight / c.weight, 1.0, 5e-4) << "cell " << i;
    }
    for (int j = 0; j < x.size(); ++j) {
      for (double s = -3.0; s <= 3.0; s += 0.5) {
        const double z = x.component(j).mean_m + s * x.component(j).sigma_m;
        worst_ll = std::max(worst_ll, std::abs(x.logLikelihood(z) - y.logLikelihood(z)));
      }
    }
  }
  // Within +-3 sigma, |d log p| <= 3 (q/2) / sigma + (d^2 + 1) * 1.4e-4 + 2.2e-4: with q = 1 mm
  // and the smallest sigma of 3 cm, 0.05 + 0.0016: a systematic 0.5 mm shift, invisible to
  // registration.
  EXPECT_LT(worst_ll, 0.052);
}

TEST(MapFormat, TileRoundTripWithinQuantisation) {
  for (bool deflate : {true, false}) {
    const GmmTile t = randomTile({3, -7}, 64, 1);
    TileCodecOptions o;
    o.deflate = deflate;
    auto enc = encodeTile(t, o);
    ASSERT_TRUE(enc.ok()) << enc.error();
    auto dec = decodeTile(enc->bytes.data(), enc->bytes.size(), "mem");
    ASSERT_TRUE(dec.ok()) << dec.error();
    // Means span 45 m: quantum 1 mm, error <= 0.5 mm (+ float rounding).
    expectClose(t, **dec, 0.5e-3 + 1e-5);
    EXPECT_EQ(enc->info.file_name, "tile_3_-7.gmt");
    EXPECT_EQ(enc->info.byte_size, enc->bytes.size());
    EXPECT_EQ(enc->info.crc32, crc32Of(enc->bytes.data(), enc->bytes.size() - 4));
    const auto hist = t.componentHistogram();
    for (int k = 0; k <= kMaxMixtureComponents; ++k)
      EXPECT_EQ(enc->info.cells_by_components[k], hist[k]);
    EXPECT_LT(enc->info.z_min_m, -5.0f);
    EXPECT_GT(enc->info.z_max_m, 40.0f);
  }
}

TEST(MapFormat, WideHeightSpanCoarsensQuantumButStaysBounded) {
  GmmTile t({0, 0}, 8);
  t.at(0, 0).add({1.f, -100.f, 0.05f});
  t.at(1, 0).add({1.f, 400.f, 0.05f});
  t.at(2, 0).add({1.f, 123.4567f, 0.05f});
  auto enc = encodeTile(t);
  ASSERT_TRUE(enc.ok());
  auto dec = decodeTile(enc->bytes.data(), enc->bytes.size(), "mem");
  ASSERT_TRUE(dec.ok());
  const double q = 500.0 / 65534.0;  // documented: span / 65534 when above 1 mm
  EXPECT_NEAR((*dec)->at(2, 0).component(0).mean_m, 123.4567, q / 2 + 1e-4);
  EXPECT_FLOAT_EQ((*dec)->at(0, 0).component(0).mean_m, -100.f);
}

TEST(MapFormat, EmptyTileRoundTrip) {
  GmmTile t({-1, 2}, 16);
  auto enc = encodeTile(t);
  ASSERT_TRUE(enc.ok());
  auto dec = decodeTile(enc->bytes.data(), enc->bytes.size(), "mem");
  ASSERT_TRUE(dec.ok()) << dec.error();
  EXPECT_EQ((*dec)->componentHistogram()[0], 256u);
  EXPECT_EQ(enc->info.z_min_m, 0.f);
}

TEST(MapFormat, EncoderRejectsInvalidValues) {
  GmmTile t({0, 0}, 8);
  t.at(1, 2).add({1.f, NAN, 0.1f});
  auto r = encodeTile(t);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("cell (1, 2)"), std::string::npos) << r.error();
  t.at(1, 2).clear();
  t.at(1, 2).add({1.f, 0.f, 0.f});
  EXPECT_FALSE(encodeTile(t).ok());
  t.at(1, 2).clear();
  t.at(1, 2).add({0.f, 0.f, 0.1f});
  t.at(1, 2).add({1.f, 1.f, 0.1f});
  EXPECT_FALSE(encodeTile(t).ok());
}

void expectFailureNaming(const Result<std::shared_ptr<GmmTile>>& r, const std::string& what) {
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("'victim.gmt'"), std::string::npos) << r.error();
  EXPECT_NE(r.error().find(what), std::string::npos) << r.error();
}

TEST(MapFormat, EveryTruncationIsDetected) {
  auto enc = encodeTile(randomTile({0, 0}, 16, 2));
  ASSERT_TRUE(enc.ok());
  const auto& b = enc->bytes;
  for (size_t n = 0; n < b.size(); ++n) {
    auto r = decodeTile(b.data(), n, "victim.gmt");
    ASSERT_FALSE(r.ok()) << "prefix of " << n << " bytes was accepted";
    const std::string& e = r.error();
    EXPECT_TRUE(e.find("truncated") != std::string::npos ||
                e.find("inconsistent sizes") != std::string::npos)
        << "n=" << n << ": " << e;
  }
}

TEST(MapFormat, EverySingleBitFlipIsDetected) {
  for (bool deflate : {true, false}) {
    TileCodecOptions o;
    o.deflate = deflate;
    auto enc = encodeTile(randomTile({0, 0}, 16, 3), o);
    ASSERT_TRUE(enc.ok());
    for (size_t bit = 0; bit < enc->bytes.size() * 8; ++bit) {
      auto b = enc->bytes;
      b[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
      auto r = decodeTile(b.data(), b.size(), "victim.gmt");
      ASSERT_FALSE(r.ok()) << "flip of bit " << bit << " was accepted";
      EXPECT_NE(r.error().find("victim.gmt"), std::string::npos);
    }
  }
}

/// Rewrites the CRC trailer so that only the field under test is wrong.
void refreshCrc(std::vector<uint8_t>& b) {
  const uint32_t crc = crc32Of(b.data(), b.size() - 4);
  for (int i = 0; i < 4; ++i) b[b.size() - 4 + i] = static_cast<uint8_t>(crc >> (8 * i));
}

TEST(MapFormat, WrongMagicAndVersion) {
  auto enc = encodeTile(randomTile({0, 0}, 8, 4));
  ASSERT_TRUE(enc.ok());
  auto b = enc->bytes;
  b[0] = 'X';
  refreshCrc(b);
  expectFailureNaming(decodeTile(b.data(), b.size(), "victim.gmt"), "wrong magic");
  b = enc->bytes;
  b[4] = 2;
  refreshCrc(b);
  expectFailureNaming(decodeTile(b.data(), b.size(), "victim.gmt"), "unsupported format version 2");
  // A valid file of another tile or tile size is refused when the caller expects another.
  const TileId other{5, 5};
  expectFailureNaming(decodeTile(enc->bytes.data(), enc->bytes.size(), "victim.gmt", &other),
                      "expected (5, 5)");
  expectFailureNaming(decodeTile(enc->bytes.data(), enc->bytes.size(), "victim.gmt", nullptr, 16),
                      "the map uses 16");
}

TEST(MapFormat, InconsistentRawSizeWithValidCrcIsDetected) {
  TileCodecOptions o;
  o.deflate = false;
  auto enc = encodeTile(randomTile({0, 0}, 8, 5), o);
  ASSERT_TRUE(enc.ok());
  auto b = enc->bytes;
  b[20] ^= 1;  // component count
  refreshCrc(b);
  expectFailureNaming(decodeTile(b.data(), b.size(), "victim.gmt"), "inconsistent sizes");
}

TEST(MapFormat, CorruptionBehindAValidCrcNeverCrashesOrYieldsInvalidValues) {
  // Beyond what a CRC catches (an adversarial or buggy writer): mutate bytes, refresh the CRC,
  // and require either a clean failure or a tile whose every value is usable.
  for (bool deflate : {true, false}) {
    TileCodecOptions o;
    o.deflate = deflate;
    auto enc = encodeTile(randomTile({0, 0}, 16, 8), o);
    ASSERT_TRUE(enc.ok());
    std::mt19937 rng(11);
    int accepted = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      auto b = enc->bytes;
      const int edits = 1 + trial % 4;
      for (int e = 0; e < edits; ++e) {
        b[std::uniform_int_distribution<size_t>(0, b.size() - 5)(rng)] =
            static_cast<uint8_t>(rng());
      }
      refreshCrc(b);
      auto r = decodeTile(b.data(), b.size(), "victim.gmt");
      if (!r.ok()) continue;
      ++accepted;
      for (const auto& cell : (*r)->cells()) {
        double sum = 0.0;
        for (int j = 0; j < cell.size(); ++j) {
          const auto& c = cell.component(j);
          ASSERT_TRUE(std::isfinite(c.mean_m));
          ASSERT_TRUE(std::isfinite(c.sigma_m) && c.sigma_m > 0.f);
          ASSERT_TRUE(c.weight > 0.f && c.weight <= 1.f);
          sum += c.weight;
        }
        if (cell.size() > 0) {
          ASSERT_NEAR(sum, 1.0, 1e-5);
        }
      }
    }
    // Edits of quantised codes decode to other valid values: some trials are accepted.
    EXPECT_GT(accepted, 0);
  }
}

MapManifest sampleManifest() {
  MapManifest m;
  m.geometry.resolution_m = 0.2;
  m.geometry.tile_size_cells = 16;
  m.geometry.origin_x_m = -12.5;
  m.geometry.origin_y_m = 7.25;
  m.georeference.present = true;
  m.georeference.datum = "WGS84 / UTM zone 17N";
  m.georeference.origin_easting_m = 277000.5;
  m.georeference.origin_northing_m = 4686000.25;
  m.provenance = "build_map test";
  for (int i = 0; i < 3; ++i) {
    TileInfo t;
    t.id = {i, -i};
    t.file_name = tileFileName(t.id);
    t.byte_size = 1000 + i;
    t.crc32 = 0xdeadbeef + i;
    t.z_min_m = -2.f;
    t.z_max_m = 10.f + i;
    t.cells_by_components = {100, 100, 50, 6};
    m.tiles.push_back(t);
  }
  return m;
}

TEST(MapFormat, ManifestRoundTripAndCorruption) {
  const MapManifest m = sampleManifest();
  const auto b = encodeManifest(m);
  auto r = decodeManifest(b.data(), b.size(), "m.gmm");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->geometry.tile_size_cells, 16);
  EXPECT_EQ(r->geometry.origin_y_m, 7.25);
  EXPECT_EQ(r->georeference.datum, m.georeference.datum);
  EXPECT_EQ(r->georeference.origin_northing_m, 4686000.25);
  EXPECT_EQ(r->provenance, "build_map test");
  ASSERT_EQ(r->tiles.size(), 3u);
  EXPECT_EQ(r->tiles[2].id, (TileId{2, -2}));
  EXPECT_EQ(r->tiles[2].crc32, 0xdeadbeefu + 2);
  EXPECT_EQ(r->tiles[1].cells_by_components[3], 6u);
  for (size_t n = 0; n < b.size(); ++n) {
    ASSERT_FALSE(decodeManifest(b.data(), n, "m.gmm").ok()) << "prefix " << n;
  }
  for (size_t bit = 0; bit < b.size() * 8; ++bit) {
    auto c = b;
    c[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    auto d = decodeManifest(c.data(), c.size(), "m.gmm");
    ASSERT_FALSE(d.ok()) << "bit " << bit;
    EXPECT_NE(d.error().find("manifest 'm.gmm'"), std::string::npos);
  }
  auto c = b;
  c[4] = 9;
  refreshCrc(c);
  EXPECT_NE(
      decodeManifest(c.data(), c.size(), "m.gmm").error().find("unsupported format version 9"),
      std::string::npos);
}

TEST(MapFormat, ManifestRejectsUnsafeNamesAndBadCounts) {
  MapManifest m = sampleManifest();
  m.tiles[1].file_name = "../etc/passwd";
  auto b = encodeManifest(m);
  EXPECT_NE(decodeManifest(b.data(), b.size(), "m").error().find("unsafe file name"),
            std::string::npos);
  m = sampleManifest();
  m.tiles[0].cells_by_components[0] = 5;
  b = encodeManifest(m);
  EXPECT_NE(decodeManifest(b.data(), b.size(), "m").error().find("inconsistent sizes"),
            std::string::npos);
  m = sampleManifest();
  m.tiles[2].id = m.tiles[0].id;
  b = encodeManifest(m);
  EXPECT_NE(decodeManifest(b.data(), b.size(), "m").error().find("listed twice"),
            std::string::npos);
}

TEST(MapFormat, FilesOnDisk) {
  TempDir dir("gmm_map_format");
  const GmmTile t = randomTile({1, 1}, 16, 6);
  auto enc = encodeTile(t);
  ASSERT_TRUE(enc.ok());
  ASSERT_TRUE(writeFileAtomic(dir.path + "/" + enc->info.file_name, enc->bytes).ok());
  MapManifest m;
  m.geometry.tile_size_cells = 16;
  m.tiles.push_back(enc->info);
  ASSERT_TRUE(writeManifest(dir.path, m).ok());
  auto mr = readManifest(dir.path);
  ASSERT_TRUE(mr.ok()) << mr.error();
  auto tr = readTileFile(dir.path, mr->tiles[0], mr->geometry);
  ASSERT_TRUE(tr.ok()) << tr.error();
  expectClose(t, **tr, 0.5e-3 + 1e-5);
  EXPECT_EQ(dir.entries().size(), 2u);  // no temporary files left behind

  // Missing manifest and missing tile: the error names the file and says "missing".
  TempDir empty("gmm_map_format");
  auto missing = readManifest(empty.path);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find(empty.path + "/manifest.gmm"), std::string::npos);
  EXPECT_NE(missing.error().find("missing"), std::string::npos);
  TileInfo ghost = enc->info;
  ghost.file_name = "tile_9_9.gmt";
  auto g = readTileFile(dir.path, ghost, m.geometry);
  ASSERT_FALSE(g.ok());
  EXPECT_NE(g.error().find("tile_9_9.gmt': missing"), std::string::npos) << g.error();

  // Truncated or replaced file: size and CRC are checked against the manifest.
  const std::string path = dir.path + "/" + enc->info.file_name;
  fs::resize_file(path, enc->bytes.size() - 3);
  auto tr2 = readTileFile(dir.path, mr->tiles[0], mr->geometry);
  ASSERT_FALSE(tr2.ok());
  EXPECT_NE(tr2.error().find("manifest says"), std::string::npos) << tr2.error();
  auto other = encodeTile(randomTile({1, 1}, 16, 7));
  ASSERT_TRUE(writeFileAtomic(path, other->bytes).ok());
  TileInfo same_size = mr->tiles[0];
  same_size.byte_size = other->bytes.size();
  auto tr3 = readTileFile(dir.path, same_size, mr->geometry);
  ASSERT_FALSE(tr3.ok());
  EXPECT_NE(tr3.error().find("CRC-32 mismatch against the manifest"), std::string::npos);
}

TEST(MapFormat, FailedAtomicWriteLeavesNoPartialFile) {
  TempDir dir("gmm_map_format");
  const std::string path = dir.path + "/data.bin";
  const std::vector<uint8_t> old_bytes(100, 7);
  ASSERT_TRUE(writeFileAtomic(path, old_bytes).ok());
  // Make the write itself fail half-way: a file size limit (SIGXFSZ ignored, write gets EFBIG).
  struct rlimit saved;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  auto old_handler = signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const Status s = writeFileAtomic(path, std::vector<uint8_t>(1 << 20, 1));
  setrlimit(RLIMIT_FSIZE, &saved);
  signal(SIGXFSZ, old_handler);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("write of"), std::string::npos) << s.error();
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"data.bin"});  // no temporary file
  auto back = readFileBytes(path);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(*back, old_bytes);  // the previous content is intact

  // Rename onto a directory fails: the temporary file is removed too.
  fs::create_directory(dir.path + "/sub");
  EXPECT_FALSE(writeFileAtomic(dir.path + "/sub", old_bytes).ok());
  EXPECT_EQ(dir.entries().size(), 2u);
  // Directory that does not exist: clear failure, nothing created.
  const Status s2 = writeFileAtomic(dir.path + "/nope/x.bin", old_bytes);
  ASSERT_FALSE(s2.ok());
  EXPECT_NE(s2.error().find("nope/x.bin"), std::string::npos);
}

// --- physical bounds on top of the CRC ---

void putF64(std::vector<uint8_t>& b, size_t at, double v) {
  uint64_t u;
  std::memcpy(&u, &v, 8);
  for (int i = 0; i < 8; ++i) b[at + i] = static_cast<uint8_t>(u >> (8 * i));
}

TEST(MapFormat, ManifestRejectsGeometryOutsidePhysicalBounds) {
  for (double res : {5e-4, 0.049, 10.5}) {
    MapManifest m = sampleManifest();
    m.geometry.resolution_m = res;
    const auto b = encodeManifest(m);
    auto r = decodeManifest(b.data(), b.size(), "m.gmm");
    ASSERT_FALSE(r.ok()) << res;
    EXPECT_NE(r.error().find("resolution_m"), std::string::npos) << r.error();
    EXPECT_NE(r.error().find("manifest 'm.gmm'"), std::string::npos) << r.error();
  }
  for (double res : {0.05, 0.2, 10.0}) {
    MapManifest m = sampleManifest();
    m.geometry.resolution_m = res;
    const auto b = encodeManifest(m);
    EXPECT_TRUE(decodeManifest(b.data(), b.size(), "m.gmm").ok()) << res;
  }
  MapManifest m = sampleManifest();
  m.geometry.origin_x_m = 1e12;
  auto b = encodeManifest(m);
  EXPECT_NE(decodeManifest(b.data(), b.size(), "m").error().find("origin"), std::string::npos);
  // Tile (2e6, 0) of 16 cells of 0.2 m lies 6400 km from the origin.
  m = sampleManifest();
  m.tiles[1].id = {2000000, 0};
  m.tiles[1].file_name = tileFileName(m.tiles[1].id);
  b = encodeManifest(m);
  auto r = decodeManifest(b.data(), b.size(), "m");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("tile (2000000, 0) lies beyond"), std::string::npos) << r.error();
  m = sampleManifest();
  m.tiles[2].z_max_m = 7e4f;
  b = encodeManifest(m);
  r = decodeManifest(b.data(), b.size(), "m");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("tile (2, -2): z range"), std::string::npos) << r.error();
}

TEST(MapFormat, DecoderRejectsCrcCorrectTileWithAbsurdComponents) {
  TileCodecOptions o;
  o.deflate = false;
  GmmTile t({4, -1}, 8);
  t.at(3, 0).add({1.f, 13.f, 0.05f});
  auto enc = encodeTile(t, o);
  ASSERT_TRUE(enc.ok()) << enc.error();
  ASSERT_TRUE(decodeTile(enc->bytes.data(), enc->bytes.size(), "victim.gmt").ok());
  // Base height (offset 24) moved to 70 km: every mean decodes there.
  auto b = enc->bytes;
  putF64(b, 24, 7e4);
  refreshCrc(b);
  auto r = decodeTile(b.data(), b.size(), "victim.gmt");
  expectFailureNaming(r, "cell (3, 0) of tile (4, -1), component 0: mean 70000");
  // Sigma code (raw payload: 16 bytes of K, 2 of mean codes, then the sigma plane) at its
  // maximum: 1e4 m.
  b = enc->bytes;
  b[48 + 18] = 0xff;
  b[48 + 19] = 0xff;
  refreshCrc(b);
  expectFailureNaming(decodeTile(b.data(), b.size(), "victim.gmt"), "component 0: sigma 10000");
  // The encoder refuses what the decoder would reject.
  t.at(3, 0).clear();
  t.at(3, 0).add({1.f, 2e4f, 0.05f});
  auto e = encodeTile(t);
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().find("physical height range"), std::string::npos) << e.error();
  t.at(3, 0).clear();
  t.at(3, 0).add({1.f, 0.f, 2e3f});
  EXPECT_FALSE(encodeTile(t).ok());
}

TEST(MapFormat, TileExtentAndComponentBoundsHelpers) {
  MapGeometry g;  // 0.2 m, 320 cells: 64 m tiles
  EXPECT_TRUE(checkTileExtent(g, {15623, -15624}).empty());
  EXPECT_FALSE(checkTileExtent(g, {15625, 0}).empty());
  EXPECT_FALSE(checkTileExtent(g, {0, -15626}).empty());
  EXPECT_FALSE(checkTileExtent(g, {INT32_MIN, INT32_MAX}).empty());
  EXPECT_TRUE(checkComponentBounds({0.5f, -400.f, 0.03f}).empty());
  EXPECT_FALSE(checkComponentBounds({0.5f, NAN, 0.03f}).empty());
  EXPECT_FALSE(checkComponentBounds({0.5f, 0.f, 0.f}).empty());
  EXPECT_FALSE(checkComponentBounds({0.5f, 0.f, INFINITY}).empty());
  EXPECT_FALSE(checkComponentBounds({-0.5f, 0.f, 1.f}).empty());
  EXPECT_FALSE(checkComponentBounds({NAN, 0.f, 1.f}).empty());
}

}  // namespace
}  // namespace gmm_localization
