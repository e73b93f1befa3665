// build_map's PCD input (pcd_reader.h, PcdSource): files written by PCL in every format, files
// written here field by field (F8 UTM coordinates, integer types, multi-element fields), and
// the malformed files that used to crash build_map or lose data silently: truncated files,
// garbled headers, short data, binary_compressed files with lying sizes, junk points. PCL only
// writes fixtures.
#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "../../unit/support/temp_dir.h"
#include "build_map/build_map_options.h"
#include "build_map/build_map_readers.h"
#include "build_map/lzf.h"
#include "build_map/pcd_reader.h"

namespace gmm_localization {
namespace tools {
namespace {

namespace fs = std::filesystem;

using testing::TempDir;

std::string readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// ---- a PCD writer of our own, for types and layouts PCL's templated writer does not make ----

struct Field {
  std::string name;
  char type = 'F';
  int size = 4;
  int count = 1;
};

std::string encode(double v, char type, int size) {
  std::string b(size, '\0');
  auto put = [&](auto x) { std::memcpy(&b[0], &x, sizeof x); };
  if (type == 'F') {
    if (size == 4)
      put(static_cast<float>(v));
    else
      put(v);
  } else if (type == 'I') {
    if (size == 1) put(static_cast<int8_t>(v));
    if (size == 2) put(static_cast<int16_t>(v));
    if (size == 4) put(static_cast<int32_t>(v));
    if (size == 8) put(static_cast<int64_t>(v));
  } else {
    if (size == 1) put(static_cast<uint8_t>(v));
    if (size == 2) put(static_cast<uint16_t>(v));
    if (size == 4) put(static_cast<uint32_t>(v));
    if (size == 8) put(static_cast<uint64_t>(v));
  }
  return b;
}

std::string header(const std::vector<Field>& fields, size_t points, const std::string& data) {
  std::string names, sizes, types, counts;
  for (const Field& f : fields) {
    names += " " + f.name;
    sizes += " " + std::to_string(f.size);
    types += std::string(" ") + f.type;
    counts += " " + std::to_string(f.count);
  }
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS" + names + "\nSIZE" +
         sizes + "\nTYPE" + types + "\nCOUNT" + counts + "\nWIDTH " + std::to_string(points) +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) + "\nDATA " +
         data + "\n";
}

/// rows[i]: point i's numbers, field after field (sum of COUNT numbers).
std::string pcdBytes(const std::vector<Field>& fields, const std::vector<std::vector<double>>& rows,
                     PcdData kind) {
  std::string out = header(fields, rows.size(), PcdHeader::dataName(kind));
  if (kind == PcdData::kAscii) {
    for (const auto& r : rows) {
      char buf[64];
      for (size_t k = 0; k < r.size(); ++k) {
        std::snprintf(buf, sizeof buf, "%s%.17g", k ? " " : "", r[k]);
        out += buf;
      }
      out += "\n";
    }
    return out;
  }
  std::string data;
  if (kind == PcdData::kBinary) {
    for (const auto& r : rows) {
      size_t k = 0;
      for (const Field& f : fields)
        for (int c = 0; c < f.count; ++c) data += encode(r[k++], f.type, f.size);
    }
    return out + data;
  }
  size_t first = 0;  // column-wise: every point's field 0, then field 1, ...
  for (const Field& f : fields) {
    for (const auto& r : rows)
      for (int c = 0; c < f.count; ++c) data += encode(r[first + c], f.type, f.size);
    first += f.count;
  }
  std::string packed(data.size() * 2 + 64, '\0');
  // An empty cloud is two zero size words (PCL's writer does the same).
  const unsigned n =
      data.empty() ? 0 : pcl::lzfCompress(data.data(), data.size(), &packed[0], packed.size());
  EXPECT_TRUE(n > 0 || data.empty());
  packed.resize(n);
  const uint32_t sizes[2] = {n, static_cast<uint32_t>(data.size())};
  return out + std::string(reinterpret_cast<const char*>(sizes), 8) + packed;
}

struct ReadAll {
  bool ok = false;
  std::string error;
  std::vector<Eigen::Vector3f> points;
  std::vector<size_t> batch_sizes;
  std::vector<std::string> warnings;
  std::string dropped;
};

std::string joined(const std::vector<std::string>& w) {
  std::string s;
  for (const auto& x : w) s += x + "\n";
  return s;
}

ReadAll readAll(const PcdSourceOptions& o) {
  ReadAll r;
  auto src = PcdSource::open(o);
  if (!src) {
    r.error = src.error();
    return r;
  }
  PointBatch b;
  for (;;) {
    auto more = (*src)->next(b);
    if (!more) {
      r.error = more.error();
      break;
    }
    if (!*more) {
      r.ok = true;
      break;
    }
    EXPECT_FALSE(b.has_sensor_origin);
    r.batch_sizes.push_back(b.points_m.size());
    r.points.insert(r.points.end(), b.points_m.begin(), b.points_m.end());
  }
  r.warnings = (*src)->takeWarnings();
  r.dropped = (*src)->dropped();
  return r;
}

ReadAll readFile(const std::string& path, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  PcdSourceOptions o;
  o.paths = {path};
  o.offset_m = offset;
  return readAll(o);
}

pcl::PointCloud<pcl::PointXYZI> lineCloud(int n) {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  for (int i = 0; i < n; ++i) {
    pcl::PointXYZI p;
    p.x = 1000.f + i * 0.25f;
    p.y = 2000.f;
    p.z = 0.5f;
    p.intensity = 7.f;
    cloud.push_back(p);
  }
  return cloud;
}

const std::vector<Field> kXyzF8 = {
    {"x", 'F', 8}, {"y", 'F', 8}, {"z", 'F', 8}, {"intensity", 'F', 4}};
const PcdData kAllKinds[] = {PcdData::kAscii, PcdData::kBinary, PcdData::kBinaryCompressed};

// ---- well-formed files ----

TEST(PcdSource, ReadsPclFilesInAllThreeFormatsInBatchesWithOffset) {
  TempDir dir("gmm_pcd");
  const auto cloud = lineCloud(2500);
  const std::string a = dir.path + "/a.pcd", b = dir.path + "/b.pcd", c = dir.path + "/c.pcd";
  ASSERT_EQ(pcl::io::savePCDFileASCII(a, cloud), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinary(b, cloud), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(c, cloud), 0);
  for (const std::string& path : {a, b, c}) {
    PcdSourceOptions o;
    o.paths = {path};
    o.batch_points = 1000;
    o.offset_m = Eigen::Vector3d(1000.0, 2000.0, 0.0);
    auto src = PcdSource::open(o);
    ASSERT_TRUE(src.ok()) << src.error();
    EXPECT_EQ((*src)->sizeHint(), 3u);
    EXPECT_EQ((*src)->points(), 2500u);
    EXPECT_NE((*src)->describe().find("intensity F4"), std::string::npos) << (*src)->describe();
    ReadAll r = readAll(o);
    ASSERT_TRUE(r.ok) << path << ": " << r.error;
    EXPECT_EQ(r.batch_sizes, (std::vector<size_t>{1000, 1000, 500})) << path;
    ASSERT_EQ(r.points.size(), 2500u);
    for (int i = 0; i < 2500; ++i) {
      ASSERT_NEAR(r.points[i].x(), i * 0.25, 1e-4) << path << " point " << i;
      ASSERT_NEAR(r.points[i].y(), 0.0, 1e-4);
      ASSERT_NEAR(r.points[i].z(), 0.5, 1e-6);
    }
    EXPECT_TRUE(r.warnings.empty()) << joined(r.warnings);
    EXPECT_EQ(r.dropped, "none");
  }
  ReadAll missing = readFile(dir.path + "/none.pcd");
  ASSERT_FALSE(missing.ok);
  EXPECT_NE(missing.error.find("none.pcd"), std::string::npos) << missing.error;
}

TEST(PcdSource, DoubleUtmCoordinatesLandWithinAMillimetreAfterTheOffset) {
  TempDir dir("gmm_pcd");
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 300; ++i)
    rows.push_back({500000.1234 + 0.01 * i, 4500000.5678 - 0.02 * i, 200.789 + 0.001 * i, 3.0});
  const Eigen::Vector3d offset(500000.0, 4500000.0, 200.0);
  for (PcdData kind : kAllKinds) {
    const std::string path = dir.path + "/utm_" + PcdHeader::dataName(kind) + ".pcd";
    writeBytes(path, pcdBytes(kXyzF8, rows, kind));
    ReadAll r = readFile(path, offset);
    ASSERT_TRUE(r.ok) << r.error;
    ASSERT_EQ(r.points.size(), rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(r.points[i][k], rows[i][k] - offset[k], 1e-3) << PcdHeader::dataName(kind);
    }
    EXPECT_TRUE(r.warnings.empty()) << joined(r.warnings);
    // Without the offset the map frame is 4500 km from its origin: a warning, not silence.
    ReadAll far = readFile(path);
    ASSERT_TRUE(far.ok) << far.error;
    EXPECT_NE(joined(far.warnings).find("give --offset"), std::string::npos)
        << joined(far.warnings);
  }
}

TEST(PcdSource, Float32UtmCoordinatesWarnOnce) {
  TempDir dir("gmm_pcd");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 100; ++i) cloud.push_back(pcl::PointXYZ(500000.f + i, 4500000.f, 10.f));
  const std::string path = dir.path + "/utm_f4.pcd";
  ASSERT_EQ(pcl::io::savePCDFileBinary(path, cloud), 0);
  ReadAll r = readFile(path, Eigen::Vector3d(500000.0, 4500000.0, 0.0));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.points.size(), 100u);
  ASSERT_EQ(r.warnings.size(), 1u) << joined(r.warnings);
  EXPECT_NE(r.warnings[0].find("float32 (F4)"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("quantised"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("utm_f4.pcd"), std::string::npos) << r.warnings[0];
}

TEST(PcdSource, DecodesEveryNumericTypeAndMultiElementFields) {
  TempDir dir("gmm_pcd");
  const std::vector<Field> fields = {{"normal", 'F', 4, 3}, {"ring", 'U', 2},        {"x", 'I', 4},
                                     {"pad", 'U', 1, 5},    {"y", 'U', 2},           {"z", 'I', 1},
                                     {"t", 'F', 8},         {"reflectivity", 'U', 1}};
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 50; ++i)
    rows.push_back({0.1, 0.2, 0.3, 7.0, -100.0 - i, 1, 2, 3, 4, 5, 60000.0 - i, -5.0, 0.25, 9});
  for (PcdData kind : kAllKinds) {
    const std::string path = dir.path + "/types.pcd";
    writeBytes(path, pcdBytes(fields, rows, kind));
    ReadAll r = readFile(path);
    ASSERT_TRUE(r.ok) << PcdHeader::dataName(kind) << ": " << r.error;
    ASSERT_EQ(r.points.size(), rows.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      ASSERT_EQ(r.points[i], Eigen::Vector3f(-100.f - i, 60000.f - i, -5.f))
          << PcdHeader::dataName(kind) << " point " << i;
    }
  }
  auto h = parsePcdHeader(header(fields, 50, "binary"));
  ASSERT_TRUE(h.ok()) << h.error();
  EXPECT_EQ(h->point_bytes, 12u + 2 + 4 + 5 + 2 + 1 + 8 + 1);
  EXPECT_EQ(h->fields[h->x].offset, 14u);
  EXPECT_EQ(h->intensity, 7);
  EXPECT_EQ(h->tokens, 14u);
}

TEST(PcdSource, SeveralFilesAndADirectoryOfTiles) {
  TempDir dir("gmm_pcd");
  const std::string tiles = dir.path + "/tiles";
  fs::create_directory(tiles);
  auto tile = [](double x0, int n) {
    std::vector<std::vector<double>> rows;
    for (int i = 0; i < n; ++i) rows.push_back({x0 + i, 0.0, 0.0, 1.0});
    return rows;
  };
  writeBytes(tiles + "/b_tile.pcd", pcdBytes(kXyzF8, tile(100, 3), PcdData::kBinary));
  writeBytes(tiles + "/a_tile.pcd", pcdBytes(kXyzF8, tile(0, 5), PcdData::kAscii));
  writeBytes(tiles + "/c_tile.PCD", pcdBytes(kXyzF8, tile(200, 2), PcdData::kBinaryCompressed));
  writeBytes(tiles + "/readme.txt", "not a tile");
  fs::create_directory(tiles + "/sub.pcd");  // a directory, not a tile
  PcdSourceOptions o;
  o.paths = {tiles};
  o.batch_points = 4;
  auto src = PcdSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  ASSERT_EQ((*src)->files().size(), 3u);
  EXPECT_NE((*src)->files()[0].find("a_tile.pcd"), std::string::npos);
  EXPECT_NE((*src)->files()[2].find("c_tile.PCD"), std::string::npos);
  EXPECT_EQ((*src)->points(), 10u);
  EXPECT_EQ((*src)->sizeHint(), 4u);  // 5 -> 4 + 1, 3, 2: batches never span files
  ReadAll r = readAll(o);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.batch_sizes, (std::vector<size_t>{4, 1, 3, 2}));
  ASSERT_EQ(r.points.size(), 10u);
  EXPECT_EQ(r.points[0].x(), 0.f);
  EXPECT_EQ(r.points[5].x(), 100.f);
  EXPECT_EQ(r.points[9].x(), 201.f);

  // Files given one by one, in the order given.
  o.paths = {tiles + "/c_tile.PCD", tiles + "/a_tile.pcd"};
  r = readAll(o);
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.points.size(), 7u);
  EXPECT_EQ(r.points[0].x(), 200.f);

  // One bad tile fails the whole input, naming it, before any point is produced.
  std::string bad = pcdBytes(kXyzF8, tile(300, 4), PcdData::kBinary);
  writeBytes(tiles + "/b_tile.pcd", bad.substr(0, bad.size() - 10));
  o.paths = {tiles};
  auto failed = PcdSource::open(o);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().find("b_tile.pcd"), std::string::npos) << failed.error();
  EXPECT_NE(failed.error().find("file 2 of 3"), std::string::npos) << failed.error();

  const std::string empty = dir.path + "/empty";
  fs::create_directory(empty);
  o.paths = {empty};
  failed = PcdSource::open(o);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().find("holds no *.pcd"), std::string::npos) << failed.error();
}

TEST(PcdSource, TransformFirstThenOffset) {
  TempDir dir("gmm_pcd");
  const std::string path = dir.path + "/fastlio.pcd";
  writeBytes(path,
             pcdBytes(kXyzF8, {{1.0, 0.0, 0.0, 1.0}, {0.0, 1.0, 0.0, 1.0}}, PcdData::kBinary));
  const char* argv[] = {"build_map",   "--output",       "/tmp/m",   "--pcd",  path.c_str(),
                        "--transform", "10,0,0,90,0,90", "--offset", "10,0,0", "--max-abs-z",
                        "100"};
  auto c = parseBuildMapArgs(11, const_cast<char**>(argv));
  ASSERT_TRUE(c.ok()) << c.error();
  PcdSourceOptions o;
  o.paths = c->pcd_paths;
  o.world_T_file = c->pcd_world_T_file;
  o.offset_m = c->offset_m;
  o.max_abs_z_m = c->pcd_max_abs_z_m;
  EXPECT_EQ(o.max_abs_z_m, 100.0);
  ReadAll r = readAll(o);
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.points.size(), 2u);
  // roll 90 (y -> z), then yaw 90 (x -> y), then +10 x; the offset takes the 10 back.
  EXPECT_TRUE(r.points[0].isApprox(Eigen::Vector3f(0.f, 1.f, 0.f), 1e-6f))
      << r.points[0].transpose();
  EXPECT_TRUE(r.points[1].isApprox(Eigen::Vector3f(0.f, 0.f, 1.f), 1e-6f))
      << r.points[1].transpose();
  auto src = PcdSource::open(o);
  ASSERT_TRUE(src.ok());
  EXPECT_NE((*src)->describe().find("rpy 90,0,90 deg"), std::string::npos) << (*src)->describe();
}

// ---- junk points ----

TEST(PcdSource, DropsNonFiniteAndFarOutPointsWithACountedWarning) {
  TempDir dir("gmm_pcd");
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 1000; ++i) rows.push_back({0.1 * (i % 40), 0.1 * (i / 40), 0.0, 1.0});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  rows.push_back({1.0, 1.0, 50000.0, 1.0});  // 50 km up
  rows.push_back({1.0, 1.0, 5000.0, 1.0});   // 5 km up
  rows.push_back({1.0, 1.0, -4000.0, 1.0});  // 4 km down
  rows.push_back({nan, 1.0, 0.0, 1.0});
  rows.push_back({1.0, inf, 0.0, 1.0});
  for (PcdData kind : kAllKinds) {
    const std::string path = dir.path + "/junk.pcd";
    writeBytes(path, pcdBytes(kXyzF8, rows, kind));
    ReadAll r = readFile(path);
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.points.size(), 1000u);
    for (const auto& p : r.points) ASSERT_EQ(p.z(), 0.f);
    EXPECT_EQ(r.dropped, "5 (2 non-finite, 3 with map-frame |z| > 3000 m)");
    const std::string w = joined(r.warnings);
    EXPECT_NE(w.find("dropped 5 of 1005 points: 2 non-finite, 3 out of range"), std::string::npos)
        << w;
  }
  // Nothing left at all: an error, not an empty map.
  const std::string path = dir.path + "/all_junk.pcd";
  writeBytes(path,
             pcdBytes(kXyzF8, {{0.0, 0.0, 9000.0, 1.0}, {nan, 0.0, 0.0, 1.0}}, PcdData::kBinary));
  ReadAll r = readFile(path);
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.error.find("no point kept"), std::string::npos) << r.error;
  // A file without points: an error too.
  writeBytes(path, pcdBytes(kXyzF8, {}, PcdData::kBinaryCompressed));
  r = readFile(path);
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.error.find("all_junk.pcd': no point in the data"), std::string::npos) << r.error;
  // Heights that are absolute: the offset's z brings them in range.
  writeBytes(path, pcdBytes(kXyzF8, {{0.0, 0.0, 3600.0, 1.0}}, PcdData::kBinary));
  r = readFile(path, Eigen::Vector3d(0.0, 0.0, 3600.0));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.points.size(), 1u);
}

// ---- malformed files ----

TEST(PcdReader, TruncatedFilesFailWithAReasonNeverACrash) {
  TempDir dir("gmm_pcd");
  const auto cloud = lineCloud(200);
  const std::string valid = dir.path + "/valid.pcd", cut = dir.path + "/cut.pcd";
  ASSERT_EQ(pcl::io::savePCDFileBinary(valid, cloud), 0);
  const std::string bytes = readBytes(valid);
  ASSERT_GT(bytes.size(), 270u);
  writeBytes(cut, bytes.substr(0, 270));  // the reproducer: PCL segfaulted on it
  auto r = PcdFileReader::open(cut);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("cut.pcd"), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("truncated"), std::string::npos) << r.error();

  // Every prefix of a binary and a binary_compressed file fails; an ascii prefix may end on a
  // line boundary (fewer points: fails) or inside the last number (it may parse): no crash.
  for (const char* kind : {"binary", "binary_compressed", "ascii"}) {
    const std::string k = kind;
    if (k == "binary_compressed") {
      ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(valid, cloud), 0);
    } else if (k == "ascii") {
      ASSERT_EQ(pcl::io::savePCDFileASCII(valid, cloud), 0);
    }
    const std::string full = readBytes(valid);
    ASSERT_TRUE(PcdFileReader::open(valid).ok()) << kind;
    for (size_t n = 0; n < full.size(); n += (n < 400 ? 1 : 7)) {
      writeBytes(cut, full.substr(0, n));
      auto p = PcdFileReader::open(cut);
      if (k != "ascii") {
        ASSERT_FALSE(p.ok()) << kind << " prefix " << n;
        ASSERT_NE(p.error().find("cut.pcd"), std::string::npos) << p.error();
      } else if (p.ok()) {
        std::vector<Eigen::Vector3d> xyz;
        auto got = (*p)->read(1000, xyz);
        ASSERT_TRUE(got.ok()) << got.error();
        ASSERT_EQ(*got, 200u);
      }
    }
  }
}

TEST(PcdReader, GarbledHeadersAreRejectedWithTheLineAndTheProblem) {
  const std::string ok = header({{"x"}, {"y"}, {"z"}}, 2, "ascii");
  ASSERT_TRUE(parsePcdHeader(ok).ok()) << parsePcdHeader(ok).error();
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = ok;
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {replaced("VERSION 0.7", "VERSON 0.7"), "unknown keyword 'VERSON'"},
      {replaced("VERSION 0.7", "VERSION 9"), "VERSION '9' is not"},
      {replaced("SIZE 4 4 4", "SIZE 4 4"), "SIZE has 2 entries for 3 FIELDS"},
      {replaced("SIZE 4 4 4", "SIZE 4 3 4"), "is not 1, 2, 4 or 8"},
      {replaced("TYPE F F F", "TYPE F F Q"), "TYPE 'Q' of field 'z' is not F, I or U"},
      {replaced("SIZE 4 4 4", "SIZE 4 4 2"), "is F2 (floats are F4 or F8)"},
      {replaced("COUNT 1 1 1", "COUNT 1 0 1"), "COUNT '0' of field 'y'"},
      {replaced("COUNT 1 1 1", "COUNT 1 1 3"), "field 'z' has COUNT 3"},
      {replaced("WIDTH 2", "WIDTH two"), "WIDTH 'two' is not a count"},
      {replaced("WIDTH 2", "WIDTH -2"), "WIDTH '-2' is not a count"},
      {replaced("POINTS 2", "POINTS 3"), "POINTS 3 but WIDTH x HEIGHT = 2 x 1 = 2"},
      {replaced("HEIGHT 1", "HEIGHT 1\nWIDTH 2"), "WIDTH repeated (first on line 7)"},
      {replaced("WIDTH 2\nHEIGHT 1\n", "WIDTH 1099511627776\nHEIGHT 4096\n"), "too large"},
      {replaced("WIDTH 2\nHEIGHT 1\n", "WIDTH 2199023255552\nHEIGHT 1\n"), "not a count"},
      {replaced("FIELDS x y z", "FIELDS x y q"), "no z field"},
      {replaced("FIELDS x y z", "FIELDS x y x"), "field 'x' appears twice"},
      {replaced("DATA ascii", "DATA zip"), "DATA 'zip' is not ascii, binary or binary_compressed"},
      {replaced("DATA ascii\n", ""), "without a DATA line"},
      {replaced("VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 0 0 0 1 0 0"), "VIEWPOINT needs 7 numbers"},
      {replaced("VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 0 0 nan 1 0 0 0"), "VIEWPOINT needs 7"},
      {replaced("FIELDS x y z", std::string("FIELDS x y\x01z")), "is not text"},
      {replaced("TYPE F F F\n", ""), "no TYPE line"},
      {std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, '\0'), "is not text"},
      {"", "without a DATA line"},
  };
  for (const auto& [text, expected] : cases) {
    auto h = parsePcdHeader(text);
    ASSERT_FALSE(h.ok()) << "accepted:\n" << text;
    EXPECT_NE(h.error().find(expected), std::string::npos)
        << "error: " << h.error() << "\nexpected: " << expected;
  }
  // A file with a garbled header names the file (PCL threw an uncaught exception on it).
  TempDir dir("gmm_pcd");
  const std::string path = dir.path + "/garbled.pcd";
  writeBytes(path, replaced("SIZE 4 4 4", "SIZE 4 4 4 4 4") + "1 2 3\n4 5 6\n");
  auto r = PcdFileReader::open(path);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("PCD file '" + path + "': header line 4: SIZE has 5 entries"),
            std::string::npos)
      << r.error();
  // Defaults as in PCL: no VERSION, COUNT, HEIGHT, VIEWPOINT nor POINTS.
  auto minimal = parsePcdHeader("FIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 5\nDATA binary\n");
  ASSERT_TRUE(minimal.ok()) << minimal.error();
  EXPECT_EQ(minimal->points, 5u);
  EXPECT_EQ(minimal->point_bytes, 24u);
}

TEST(PcdReader, DataShorterThanTheHeaderSays) {
  TempDir dir("gmm_pcd");
  std::vector<std::vector<double>> rows(50, std::vector<double>{1.0, 2.0, 3.0, 4.0});
  std::string bytes = pcdBytes(kXyzF8, rows, PcdData::kBinary);
  const size_t at = bytes.find("WIDTH 50"), pt = bytes.find("POINTS 50");
  bytes.replace(pt, 9, "POINTS 100").replace(at, 8, "WIDTH 100");
  const std::string path = dir.path + "/short.pcd";
  writeBytes(path, bytes);
  auto r = PcdFileReader::open(path);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(
      r.error().find("holds 1400 bytes but WIDTH x HEIGHT = 100 points of 28 bytes need 2800"),
      std::string::npos)
      << r.error();
  // Longer data: read, with a note.
  std::string longer = pcdBytes(kXyzF8, rows, PcdData::kBinary) + "trailing";
  writeBytes(path, longer);
  ReadAll ok = readFile(path);
  ASSERT_TRUE(ok.ok) << ok.error;
  EXPECT_EQ(ok.points.size(), 50u);
  EXPECT_NE(joined(ok.warnings).find("8 bytes after the last point are ignored"),
            std::string::npos);
  // A VIEWPOINT is reported, not applied (as in PCL).
  std::string viewpoint = pcdBytes(kXyzF8, rows, PcdData::kBinary);
  viewpoint.replace(viewpoint.find("VIEWPOINT 0 0 0"), 15, "VIEWPOINT 5 0 0");
  writeBytes(path, viewpoint);
  ok = readFile(path);
  ASSERT_TRUE(ok.ok) << ok.error;
  EXPECT_EQ(ok.points[0], Eigen::Vector3f(1.f, 2.f, 3.f));
  EXPECT_NE(joined(ok.warnings).find("VIEWPOINT is not identity"), std::string::npos);
  // ascii: missing lines, wrong number counts, words.
  const std::string ascii = pcdBytes(kXyzF8, rows, PcdData::kAscii);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {ascii.substr(0, ascii.rfind("1 2 3 4")), "ends after 49 points but the header says 50"},
      {ascii + "1 2 3 4\n", ""},  // extra line: a note
      {ascii.substr(0, ascii.rfind("1 2 3 4")) + "1 2 3\n",
       "line 61 has 3 numbers but the fields need 4"},
      {ascii.substr(0, ascii.rfind("1 2 3 4")) + "1 2 x 4\n", "line 61: 'x' is not a number"},
      {ascii.substr(0, ascii.rfind("1 2 3 4")) + "1 2 3 4 5\n", "has 5 numbers"},
      {ascii.substr(0, ascii.rfind("1 2 3 4")) + "\n\n1 2 3 4\r\n", ""},  // blank lines, CRLF
  };
  for (const auto& [text, expected] : cases) {
    writeBytes(path, text);
    auto a = PcdFileReader::open(path);
    if (expected.empty()) {
      ASSERT_TRUE(a.ok()) << a.error();
      std::vector<Eigen::Vector3d> xyz;
      ASSERT_EQ(*(*a)->read(100, xyz), 50u);
      EXPECT_EQ(xyz.back(), Eigen::Vector3d(1, 2, 3));
      continue;
    }
    ASSERT_FALSE(a.ok()) << expected;
    EXPECT_NE(a.error().find(expected), std::string::npos) << a.error();
  }
}

TEST(PcdReader, BinaryCompressedWithLyingSizes) {
  TempDir dir("gmm_pcd");
  const auto cloud = lineCloud(1000);
  const std::string valid = dir.path + "/valid.pcd", bad = dir.path + "/bad.pcd";
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(valid, cloud), 0);
  const std::string bytes = readBytes(valid);
  auto vr = PcdFileReader::open(valid);
  ASSERT_TRUE(vr.ok()) << vr.error();
  const size_t data = (*vr)->header().data_offset;
  uint32_t sizes[2];
  std::memcpy(sizes, bytes.data() + data, 8);
  EXPECT_EQ(sizes[1], 1000u * 16);
  auto withSizes = [&](uint32_t compressed, uint32_t uncompressed) {
    std::string b = bytes;
    std::memcpy(&b[data], &compressed, 4);
    std::memcpy(&b[data + 4], &uncompressed, 4);
    return b;
  };
  auto expectFailure = [&](const std::string& b, const std::string& expected) {
    writeBytes(bad, b);
    auto r = PcdFileReader::open(bad);
    ASSERT_FALSE(r.ok()) << expected;
    EXPECT_NE(r.error().find("bad.pcd"), std::string::npos) << r.error();
    EXPECT_NE(r.error().find(expected), std::string::npos) << r.error();
  };
  expectFailure(withSizes(sizes[0], sizes[1] * 2), "the uncompressed size is 32000 bytes");
  expectFailure(withSizes(sizes[0], sizes[1] - 1), "the uncompressed size is 15999 bytes");
  expectFailure(withSizes(sizes[0] + 1000, sizes[1]),
                "only " + std::to_string(sizes[0]) + " follow");
  expectFailure(withSizes(0xffffffffu, sizes[1]), "truncated file or wrong size");
  expectFailure(withSizes(sizes[0] / 2, sizes[1]), "LZF data");
  expectFailure(withSizes(10, sizes[1]), "cannot hold 16000 bytes");
  // The header and the size word agree on a much larger cloud than the stream holds.
  std::string lying = withSizes(sizes[0], 2000 * 16);
  lying.replace(lying.find("WIDTH 1000"), 10, "WIDTH 2000")
      .replace(lying.find("POINTS 1000"), 11, "POINTS 2000");
  expectFailure(lying, "LZF data: data ends before the expected size");
  // Random corruption of the stream: never a crash; a success decodes exactly 1000 points.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 300; ++trial) {
    std::string b = bytes;
    for (int k = 0; k < 1 + trial % 5; ++k) b[data + 8 + rng() % (b.size() - data - 8)] = rng();
    writeBytes(bad, b);
    auto p = PcdFileReader::open(bad);
    if (!p.ok()) continue;
    std::vector<Eigen::Vector3d> xyz;
    auto got = (*p)->read(5000, xyz);
    ASSERT_TRUE(got.ok());
    ASSERT_EQ(*got, 1000u);
  }
}

TEST(Lzf, DecodesPclStreamsAndRejectsMalformedOnes) {
  std::mt19937 rng(3);
  std::vector<uint8_t> raw(20000);
  for (size_t i = 0; i < raw.size(); ++i) raw[i] = (i % 300 < 150) ? rng() % 4 : rng();
  std::vector<uint8_t> packed(raw.size() * 2);
  const unsigned n = pcl::lzfCompress(raw.data(), raw.size(), packed.data(), packed.size());
  ASSERT_GT(n, 0u);
  std::vector<uint8_t> out(raw.size());
  ASSERT_TRUE(lzfDecompress(packed.data(), n, out.data(), out.size()).ok());
  EXPECT_EQ(out, raw);
  EXPECT_NE(lzfDecompress(packed.data(), n, out.data(), out.size() - 1)
                .error()
                .find("past the expected size"),
            std::string::npos);
  std::vector<uint8_t> more(raw.size() + 1);
  EXPECT_NE(lzfDecompress(packed.data(), n, more.data(), more.size()).error().find("ends before"),
            std::string::npos);
  uint8_t o[16];
  const uint8_t literal_past_end[] = {5, 'a', 'b'};
  EXPECT_NE(lzfDecompress(literal_past_end, 3, o, 6).error().find("past the end of the input"),
            std::string::npos);
  const uint8_t ref_before_start[] = {0, 'a', 0x20, 5};  // distance 6 with 1 byte out
  EXPECT_NE(lzfDecompress(ref_before_start, 4, o, 4).error().find("before the start"),
            std::string::npos);
  const uint8_t ref_cut[] = {0, 'a', 0xe0};
  EXPECT_NE(lzfDecompress(ref_cut, 3, o, 16).error().find("past the end of the input"),
            std::string::npos);
  const uint8_t run[] = {0, 'a', 0x20, 0};  // 'a' then a 3-byte overlapping copy: "aaaa"
  ASSERT_TRUE(lzfDecompress(run, 4, o, 4).ok());
  EXPECT_EQ(std::string(reinterpret_cast<char*>(o), 4), "aaaa");
  EXPECT_TRUE(lzfDecompress(nullptr, 0, o, 0).ok());
}

// ---- command line ----

TEST(BuildMapArgs, PcdInputsTransformAndHeightLimit) {
  const char* ok[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--pcd", "tiles/"};
  auto c = parseBuildMapArgs(7, const_cast<char**>(ok));
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->pcd_paths, (std::vector<std::string>{"a.pcd", "tiles/"}));
  EXPECT_TRUE(c->pcd_world_T_file.matrix().isIdentity(0.0));
  EXPECT_EQ(c->pcd_max_abs_z_m, 3000.0);
  const char* kitti[] = {"build_map", "--output",    "/tmp/m",     "--kitti",
                         "d",         "--transform", "0,0,0,0,0,1"};
  EXPECT_NE(
      parseBuildMapArgs(7, const_cast<char**>(kitti)).error().find("--transform applies to --pcd"),
      std::string::npos);
  const char* mixed[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--bag", "b.bag"};
  EXPECT_NE(parseBuildMapArgs(7, const_cast<char**>(mixed)).error().find("exactly one input"),
            std::string::npos);
  const char* bad_z[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--max-abs-z", "0"};
  EXPECT_NE(parseBuildMapArgs(7, const_cast<char**>(bad_z)).error().find("--max-abs-z must be > 0"),
            std::string::npos);
  const char* bad_t[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--transform", "1,2"};
  EXPECT_FALSE(parseBuildMapArgs(7, const_cast<char**>(bad_t)).ok());
  const std::string help = buildMapHelp();
  for (const char* o : {"--pcd FILE|DIR", "--transform", "--max-abs-z", "binary_compressed"})
    EXPECT_NE(help.find(o), std::string::npos) << o;
}

}  // namespace
}  // namespace tools
}  // namespace gmm_localization
