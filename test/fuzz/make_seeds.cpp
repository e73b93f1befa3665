// fuzz_make_seeds OUT_DIR CONFIG_DIR: writes the seed corpus of every fuzz target into
// OUT_DIR/<target>/ (map_tile, map_manifest, pointcloud2, raster_chunk, map_index, pcd, kitti,
// yaml_params), made with the project's own writers wherever it has one: encodeTile and
// encodeManifest (map format), rasterizeChunk and node::toMsg (raster chunks), node::toMsg
// (clouds), sim::KittiWriter (KITTI scans and poses), and the package's config/*.yaml. The
// project writes no PCD files (build_map only reads them; its tests use PCL's writer), so the PCD
// seeds are written here, in PCL's layout, with a small LZF encoder for binary_compressed. The
// seeds are regenerated on every run (scripts/run_fuzz.sh), so none is stored in the
// repository. Every seed is read back with the parser its target fuzzes and must be accepted
// (else the tool fails): a seed the parser refuses would leave the fuzzer at its first check.
#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "build_map/pcd_reader.h"
#include "evaluate/evaluate_yaml.h"
#include "fuzz_input.h"
#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "gmm_localization/ros/chunk_conversion.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/cloud_merger_options.h"
#include "gmm_localization/ros/ekf_node_options.h"
#include "gmm_localization/ros/map_server_client.h"
#include "gmm_localization/ros/map_server_options.h"
#include "gmm_localization/ros/matcher_options.h"
#include "gmm_localization/sim/kitti_writer.h"

namespace {

using namespace gmm_localization;
namespace fs = std::filesystem;

std::string g_out;
int g_count = 0;

/// Empty when `target`'s parser accepts the seed written at `path`, else why not.
std::string verify(const std::string& target, const std::string& path,
                   const std::vector<uint8_t>& b);

void seed(const std::string& target, const std::string& name, const std::vector<uint8_t>& bytes) {
  const fs::path dir = fs::path(g_out) / target;
  fs::create_directories(dir);
  {
    std::ofstream f(dir / name, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
    if (!f) {
      std::cerr << "fuzz_make_seeds: cannot write " << (dir / name) << "\n";
      std::exit(1);
    }
  }
  const std::string refused = verify(target, (dir / name).string(), bytes);
  if (!refused.empty()) {
    std::cerr << "fuzz_make_seeds: the " << target << " seed " << name
              << " is refused by its parser: " << refused << "\n";
    std::exit(1);
  }
  ++g_count;
}

std::vector<uint8_t> bytesOf(const std::string& s) { return {s.begin(), s.end()}; }

std::vector<uint8_t> readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <typename T>
T need(Result<T> r, const char* what) {
  if (!r) {
    std::cerr << "fuzz_make_seeds: " << what << ": " << r.error() << "\n";
    std::exit(1);
  }
  return std::move(*r);
}

// --- map tiles and manifests ---------------------------------------------------------------

/// A tile with cells of 0 to 3 components: ground, a kerb, a wall with a canopy.
std::shared_ptr<GmmTile> makeTile(TileId id, int32_t size, int max_components) {
  auto tile = std::make_shared<GmmTile>(id, size);
  for (int32_t y = 0; y < size; ++y) {
    for (int32_t x = 0; x < size; ++x) {
      const int k = (x + 2 * y) % (max_components + 1);
      GaussianMixture1D& g = tile->at(x, y);
      const float w = 1.f / static_cast<float>(k > 0 ? k : 1);
      for (int j = 0; j < k; ++j) {
        g.add({w, -1.5f + 0.05f * x + 2.5f * j, 0.03f + 0.2f * j + 0.001f * y});
      }
    }
  }
  return tile;
}

void mapSeeds(std::vector<TileInfo>& infos) {
  TileCodecOptions raw;
  raw.deflate = false;
  const struct {
    TileId id;
    int32_t size;
    int k;
    bool deflate;
    const char* name;
  } tiles[] = {{{0, 0}, 8, 3, true, "tile_8_k3_deflate"},
               {{3, -2}, 8, 2, false, "tile_8_k2_raw"},
               {{-1, 5}, 16, 1, true, "tile_16_k1_deflate"},
               {{7, 7}, 8, 0, false, "tile_8_empty"}};
  for (const auto& t : tiles) {
    const EncodedTile e =
        need(encodeTile(*makeTile(t.id, t.size, t.k), t.deflate ? TileCodecOptions{} : raw),
             "encodeTile");
    seed("map_tile", t.name, e.bytes);
    if (t.size == 8) infos.push_back(e.info);
  }

  MapManifest m;
  m.geometry.resolution_m = 0.2;
  m.geometry.tile_size_cells = 8;
  m.geometry.origin_x_m = -12.5;
  m.geometry.origin_y_m = 40.0;
  m.georeference.present = true;
  m.georeference.datum = "WGS84 / UTM zone 17N";
  m.georeference.origin_easting_m = 630084.0;
  m.georeference.origin_northing_m = 4833438.0;
  m.georeference.origin_up_m = 76.5;
  m.provenance = "fuzz_make_seeds";
  m.tiles = infos;
  seed("map_manifest", "manifest_3_tiles_georeferenced", encodeManifest(m));
  m.layer = MapLayer::kReflectivity;  // the layer and its definition after the provenance
  m.reflectivity.ground_height_m = -1.73;
  seed("map_manifest", "manifest_3_tiles_reflectivity", encodeManifest(m));
  MapManifest empty;
  empty.geometry.tile_size_cells = 8;
  seed("map_manifest", "manifest_no_tiles", encodeManifest(empty));
}

// --- raster chunks and map indices ---------------------------------------------------------

RasterOptions chunkOptions() {
  RasterOptions o;
  o.chunk_shift = 4;
  o.num_layers = 2;
  o.z_coarsening_period = 1;
  return o;
}

GmmMap chunkMap() {
  MapGeometry g;
  g.tile_size_cells = 16;
  GmmMap map(g);
  for (int tx = 0; tx < 2; ++tx) map.insert(makeTile({tx, 0}, 16, 2));
  return map;
}

RasterChunk chunkMsg(ChunkId id, uint64_t version, double stamp_s, bool mixtures = true) {
  const MapChunkConstPtr chunk = need(rasterizeChunk(chunkMap(), id, chunkOptions()), "rasterize");
  RasterChunk msg;
  node::toMsg(*chunk, version, "map", ros::Time(stamp_s), msg);
  if (!mixtures) {
    msg.component_count.clear();
    msg.components.clear();
  }
  return msg;
}

MapIndex indexMsg(uint64_t version, double stamp_s, const std::vector<ChunkId>& ids) {
  MapIndex index;
  index.header.stamp = ros::Time(stamp_s);
  index.map_directory = "/maps/fuzz";
  index.map_version = version;
  const MapGeometry g = chunkMap().geometry();
  index.resolution_m = g.resolution_m;
  index.tile_size_cells = g.tile_size_cells;
  index.origin_x_m = g.origin_x_m;
  index.origin_y_m = g.origin_y_m;
  const RasterOptions o = chunkOptions();
  index.z_step_m = o.z_step_m;
  index.ll_floor = o.ll_floor;
  index.ll_ceiling = o.ll_ceiling;
  index.num_layers = o.num_layers;
  index.z_coarsening_period = o.z_coarsening_period;
  index.chunk_shift = o.chunk_shift;
  for (const ChunkId& id : ids) {
    index.chunk_x.push_back(id.x);
    index.chunk_y.push_back(id.y);
  }
  index.min_x_m = 0.0;
  index.min_y_m = 0.0;
  index.max_x_m = 2 * g.tileSizeM();
  index.max_y_m = g.tileSizeM();
  return index;
}

/// fuzz_map_index's op byte: bit 0 index, bits 1-2 publisher, bits 3-7 wall time step.
uint8_t op(bool index, int publisher, int half_seconds) {
  return static_cast<uint8_t>((index ? 1 : 0) | (publisher << 1) | (half_seconds << 3));
}

void rasterSeeds() {
  for (const auto& [name, msg] :
       {std::pair<const char*, RasterChunk>{"chunk_0_0", chunkMsg({0, 0}, 1, 2.0)},
        {"chunk_1_0", chunkMsg({1, 0}, 1, 2.0)},
        {"chunk_0_0_no_mixtures", chunkMsg({0, 0}, 1, 2.0, false)}}) {
    fuzz::Writer w;
    fuzz::writeChunk(w, msg);
    seed("raster_chunk", name, w.out);
  }

  {  // The usual order: the index, then its chunks, from the map server.
    fuzz::Writer w;
    w.put(op(true, 1, 0));
    fuzz::writeIndex(w, indexMsg(1, 1.0, {{0, 0}, {1, 0}}));
    w.put(op(false, 1, 1));
    fuzz::writeChunk(w, chunkMsg({0, 0}, 1, 2.0));
    w.put(op(false, 1, 1));
    fuzz::writeChunk(w, chunkMsg({1, 0}, 1, 2.0));
    seed("map_index", "index_then_chunks", w.out);
  }
  {  // A chunk before its index, then a newer map version (dropping it) and its chunk.
    fuzz::Writer w;
    w.put(op(false, 1, 0));
    fuzz::writeChunk(w, chunkMsg({0, 0}, 1, 2.0));
    w.put(op(true, 1, 1));
    fuzz::writeIndex(w, indexMsg(1, 1.0, {}));
    w.put(op(true, 1, 1));
    fuzz::writeIndex(w, indexMsg(2, 3.0, {{1, 0}}));
    w.put(op(false, 1, 1));
    fuzz::writeChunk(w, chunkMsg({1, 0}, 2, 4.0));
    seed("map_index", "chunk_first_then_new_version", w.out);
  }
  {  // A second publisher: ignored while the first speaks, adopted after its silence.
    fuzz::Writer w;
    w.put(op(true, 1, 0));
    fuzz::writeIndex(w, indexMsg(1, 1.0, {{0, 0}}));
    w.put(op(true, 2, 1));
    fuzz::writeIndex(w, indexMsg(5, 2.0, {{0, 0}}));
    w.put(op(true, 2, 31));
    fuzz::writeIndex(w, indexMsg(5, 3.0, {{0, 0}}));
    w.put(op(false, 2, 1));
    fuzz::writeChunk(w, chunkMsg({0, 0}, 5, 4.0));
    seed("map_index", "publisher_switch", w.out);
  }
}

// --- clouds --------------------------------------------------------------------------------

void cloudSeeds() {
  node::CloudData xyz;
  for (int i = 0; i < 8; ++i) xyz.points.emplace_back(0.5f * i, -1.f + i, 0.1f * i);
  sensor_msgs::PointCloud2 msg;
  node::toMsg(xyz, msg);
  seed("pointcloud2", "xyz", fuzz::writeCloud(msg));

  node::CloudData full = xyz;
  for (size_t i = 0; i < full.points.size(); ++i) {
    full.time_s.push_back(0.0125f * i);
    full.intensity.push_back(10.f * i);
    full.ring.push_back(static_cast<uint16_t>(i % 32));
    full.label.push_back(static_cast<uint8_t>(i % 3));
  }
  full.points[3].x() = NAN;
  node::toMsg(full, msg, "likelihood", std::vector<float>(full.points.size(), 0.25f));
  seed("pointcloud2", "all_fields", fuzz::writeCloud(msg));
  seed("pointcloud2", "all_fields_fixed_sizes",
       fuzz::writeCloud(msg, fuzz::kCloudFixRowStep | fuzz::kCloudFixWidth));

  // An organised float64 cloud with an Ouster-style uint32 "t" [ns] and padded rows.
  sensor_msgs::PointCloud2 ouster;
  auto field = [&](const char* name, uint32_t offset, uint8_t type) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    ouster.fields.push_back(f);
  };
  using PF = sensor_msgs::PointField;
  field("x", 0, PF::FLOAT64);
  field("y", 8, PF::FLOAT64);
  field("z", 16, PF::FLOAT64);
  field("t", 24, PF::UINT32);
  field("ring", 28, PF::UINT16);
  field("intensity", 30, PF::UINT16);
  ouster.height = 2;
  ouster.width = 3;
  ouster.point_step = 32;
  ouster.row_step = 3 * 32 + 8;
  ouster.data.assign(ouster.row_step * ouster.height, 0);
  for (uint32_t row = 0; row < 2; ++row) {
    for (uint32_t col = 0; col < 3; ++col) {
      uint8_t* p = ouster.data.data() + row * ouster.row_step + col * ouster.point_step;
      const double v[3] = {1.0 + col, -2.0 * row, 0.5};
      std::memcpy(p, v, sizeof v);
      const uint32_t t = 100000u * (3 * row + col);
      std::memcpy(p + 24, &t, 4);
      const uint16_t ring = static_cast<uint16_t>(row), intensity = 300;
      std::memcpy(p + 28, &ring, 2);
      std::memcpy(p + 30, &intensity, 2);
    }
  }
  seed("pointcloud2", "ouster_float64_padded", fuzz::writeCloud(ouster));
}

// --- PCD -----------------------------------------------------------------------------------

/// LZF (liblzf's format, as lzf.h reads it): literal runs of up to 32 bytes and back-references
/// at distance 1 for runs of a repeated byte.
std::vector<uint8_t> lzf(const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out, lit;
  auto flush = [&] {
    if (lit.empty()) return;
    out.push_back(static_cast<uint8_t>(lit.size() - 1));
    out.insert(out.end(), lit.begin(), lit.end());
    lit.clear();
  };
  size_t i = 0;
  while (i < in.size()) {
    size_t run = 0;
    while (i > 0 && i + run < in.size() && in[i + run] == in[i - 1] && run < 264) ++run;
    if (run >= 3) {
      flush();
      const size_t n = run - 2;
      if (n < 7) {
        out.push_back(static_cast<uint8_t>(n << 5));
      } else {
        out.push_back(static_cast<uint8_t>(7 << 5));
        out.push_back(static_cast<uint8_t>(n - 7));
      }
      out.push_back(0);  // distance 1
      i += run;
      continue;
    }
    lit.push_back(in[i++]);
    if (lit.size() == 32) flush();
  }
  flush();
  return out;
}

template <typename T>
void append(std::vector<uint8_t>& b, T v) {
  const auto* p = reinterpret_cast<const uint8_t*>(&v);
  b.insert(b.end(), p, p + sizeof v);
}

void pcdSeeds() {
  const int n = 6;
  auto header = [&](const std::string& fields, const std::string& size, const std::string& type,
                    const std::string& count, const std::string& data) {
    std::ostringstream h;
    h << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " << fields << "\nSIZE "
      << size << "\nTYPE " << type << "\nCOUNT " << count << "\nWIDTH " << n
      << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n << "\nDATA " << data << "\n";
    return h.str();
  };
  {
    std::string s = header("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 1", "ascii");
    for (int i = 0; i < n; ++i) {
      s += std::to_string(0.5 * i) + " " + std::to_string(-1.0 * i) + " 0.25 " +
           std::to_string(10 * i) + "\n";
    }
    seed("pcd", "ascii_xyzi.pcd", bytesOf(s));
  }
  {  // binary: float64 coordinates, a 2-element field, integer channels.
    std::vector<uint8_t> b = bytesOf(
        header("x y z normal ring label", "8 8 8 4 2 1", "F F F F U I", "1 1 1 2 1 1", "binary"));
    for (int i = 0; i < n; ++i) {
      append<double>(b, 1.0 + i);
      append<double>(b, 2.0 * i);
      append<double>(b, -0.5);
      append<float>(b, 0.f);
      append<float>(b, 1.f);
      append<uint16_t>(b, static_cast<uint16_t>(i));
      append<int8_t>(b, static_cast<int8_t>(-i));
    }
    seed("pcd", "binary_f8_mixed.pcd", b);
  }
  {  // binary_compressed: column-wise x, y, z, intensity (F4), LZF.
    std::vector<uint8_t> cols;
    for (int k = 0; k < 4; ++k) {
      for (int i = 0; i < n; ++i) append<float>(cols, k == 2 ? 0.f : static_cast<float>(i * k));
    }
    std::vector<uint8_t> b =
        bytesOf(header("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 1", "binary_compressed"));
    const std::vector<uint8_t> packed = lzf(cols);
    append<uint32_t>(b, static_cast<uint32_t>(packed.size()));
    append<uint32_t>(b, static_cast<uint32_t>(cols.size()));
    b.insert(b.end(), packed.begin(), packed.end());
    seed("pcd", "binary_compressed_xyzi.pcd", b);
  }
}

// --- KITTI ---------------------------------------------------------------------------------

std::vector<uint8_t> withMode(uint8_t mode, const std::vector<uint8_t>& rest) {
  std::vector<uint8_t> b{mode};
  b.insert(b.end(), rest.begin(), rest.end());
  return b;
}

void kittiSeeds() {
  const fs::path dir = fs::path(g_out) / ".kitti_writer";
  fs::remove_all(dir);
  auto writer = need(sim::KittiWriter::open(dir.string(), false), "KittiWriter::open");
  for (int s = 0; s < 2; ++s) {
    std::vector<sim::LidarPoint> points;
    for (int i = 0; i < 5; ++i) {
      points.push_back(
          {1.f + i, -0.5f * i, 0.2f * s, 12.f * i, 0.001f * i, static_cast<uint16_t>(i), 0});
    }
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(2.0 * s, 0.5 * s, 0.0);
    pose.linear() = Eigen::AngleAxisd(0.1 * s, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Status st = writer->write(points, pose, 0.1 * s);
    if (!st) {
      std::cerr << "fuzz_make_seeds: KittiWriter::write: " << st.error() << "\n";
      std::exit(1);
    }
  }
  const Status closed = writer->close();
  if (!closed) {
    std::cerr << "fuzz_make_seeds: KittiWriter::close: " << closed.error() << "\n";
    std::exit(1);
  }
  const std::vector<uint8_t> scan = readAll((dir / "velodyne/000000.bin").string());
  const std::vector<uint8_t> poses = readAll((dir / "poses.txt").string());
  fs::remove_all(dir);

  seed("kitti", "scan_auto_xyzi", withMode(0, scan));
  seed("kitti", "scan_xyzi", withMode(2, scan));
  std::vector<uint8_t> xyz;
  for (int i = 0; i < 3; ++i) {
    for (float v : {1.f * i, 2.f, -0.5f}) append<float>(xyz, v);
  }
  seed("kitti", "scan_xyz", withMode(1, xyz));
  seed("kitti", "poses_kitti", withMode(3, poses));
  seed("kitti", "poses_graph",
       withMode(3, bytesOf("# id x y z qx qy qz qw\nv0 0 0 0 0 0 0 1\nv1 1.5 0.2 0 0 0 "
                           "0.0499792 0.99875\n\nv3 3 0.4 0.1 0 0 0.0998 0.995\n")));
  seed("kitti", "calib",
       withMode(4, bytesOf("P0: 7.07e+02 0 6.01e+02 0 0 7.07e+02 1.83e+02 0 0 0 1 0\n"
                           "Tr: 4.27e-04 -9.99e-01 -8.08e-03 -1.19e-02 -7.21e-03 8.08e-03 "
                           "-9.99e-01 -5.40e-02 9.99e-01 4.84e-04 -7.21e-03 -2.92e-01\n")));
  seed("kitti", "index_list", withMode(5, bytesOf("0,2,4-7")));
  std::vector<uint8_t> directory = poses;
  directory.push_back(0);
  directory.insert(directory.end(), scan.begin(), scan.end());
  seed("kitti", "directory", withMode(6, directory));
}

// --- YAML parameters -----------------------------------------------------------------------

void yamlSeeds(const std::string& config_dir) {
  int files = 0;
  for (const auto& e : fs::directory_iterator(config_dir)) {
    if (e.path().extension() != ".yaml") continue;
    const std::vector<uint8_t> text = readAll(e.path().string());
    seed("yaml_params", e.path().filename().string(), text);
    ++files;
    if (e.path().filename() == "matcher.yaml") {
      std::vector<uint8_t> b = text;
      b.push_back(0);
      const std::vector<uint8_t> o = bytesOf("window/min_half_xy_m=0.5\nnum_threads=[1, 2]\n");
      b.insert(b.end(), o.begin(), o.end());
      seed("yaml_params", "matcher_with_overrides", b);
    }
  }
  if (files == 0) {
    std::cerr << "fuzz_make_seeds: no .yaml file in " << config_dir << "\n";
    std::exit(1);
  }
  seed("yaml_params", "tags_and_types",
       bytesOf("a: !!str 1\nb: !!int 0x1F\nc: !!float .inf\nd: !degrees 90\ne: [yes, Off, ~]\n"
               "f: {g: 0o17, h: 1.0e-9, i: 0b101, j: '3'}\n"));
}

// --- the seeds read back -------------------------------------------------------------------

template <typename Options>
std::string loads(Options (*loader)(const node::ParamSource&), const node::ParamSource& source) {
  try {
    (void)loader(source);
    return {};
  } catch (const node::ConfigError& e) {
    return e.what();
  }
}

std::string verifyIndexSequence(const std::vector<uint8_t>& b) {
  fuzz::Reader r(b.data(), b.size());
  node::MapServerClient client;
  double wall_s = 1000.0;
  static const char* const kPublishers[] = {"", "/map_server", "/other", "/third"};
  std::string error;
  while (r.remaining() > 0) {
    const uint8_t op = r.get<uint8_t>();
    wall_s += 0.5 * (op >> 3);
    if (op & 1) {
      auto index = fuzz::readIndex(r);
      const std::string invalid = node::validateIndex(*index);
      if (!invalid.empty()) return "index: " + invalid;
      client.onIndex(index, kPublishers[(op >> 1) & 3], ros::WallTime(wall_s), &error);
    } else {
      auto chunk = fuzz::readChunk(r);
      auto c = node::fromMsg(chunk);
      if (!c) return "chunk: " + c.error();
      client.onChunk(chunk, kPublishers[(op >> 1) & 3], ros::WallTime(wall_s), &error);
    }
  }
  if (!client.hasIndex() || client.chunks().size() == 0) return "no chunk held at the end";
  return {};
}

std::string verify(const std::string& target, const std::string& path,
                   const std::vector<uint8_t>& b) {
  if (target == "map_tile") {
    auto t = decodeTile(b.data(), b.size(), path);
    return t ? "" : t.error();
  }
  if (target == "map_manifest") {
    auto m = decodeManifest(b.data(), b.size(), path);
    return m ? "" : m.error();
  }
  if (target == "pointcloud2") {
    fuzz::Reader r(b.data(), b.size());
    auto c = node::fromMsg(fuzz::readCloud(r));
    return c ? "" : c.error();
  }
  if (target == "raster_chunk") {
    fuzz::Reader r(b.data(), b.size());
    auto c = node::fromMsg(fuzz::readChunk(r));
    return c ? "" : c.error();
  }
  if (target == "map_index") return verifyIndexSequence(b);
  if (target == "pcd") {
    auto p = tools::PcdFileReader::open(path);
    if (!p) return p.error();
    std::vector<Eigen::Vector3d> xyz;
    auto n = (*p)->read(1000, xyz);
    if (!n || *n != (*p)->header().points || *n == 0) return "read() does not give every point";
    return {};
  }
  if (target == "kitti") {
    const std::string rest = path + ".body";
    {
      std::ofstream f(rest, std::ios::binary);
      f.write(reinterpret_cast<const char*>(b.data() + 1),
              static_cast<std::streamsize>(b.size() - 1));
    }
    std::string why;
    switch (b[0]) {
      case 0:
      case 1:
      case 2: {
        auto s = readKittiScan(rest, b[0] == 0   ? KittiFields::kAuto
                                     : b[0] == 1 ? KittiFields::kXyz
                                                 : KittiFields::kXyzi);
        why = s ? "" : s.error();
        break;
      }
      case 3: {
        auto p = readKittiPoses(rest);
        why = p ? "" : p.error();
        break;
      }
      case 4: {
        auto t = readKittiCalibTr(rest);
        why = t ? "" : t.error();
        break;
      }
      case 5: {
        auto l = parseIndexList(std::string(b.begin() + 1, b.end()));
        why = l ? "" : l.error();
        break;
      }
      default:
        break;  // the directory seed: its two parts are the poses and scan seeds above
    }
    fs::remove(rest);
    return why;
  }
  if (target == "yaml_params") {
    std::vector<std::string> overrides;
    std::string text(b.begin(), b.end());
    const size_t nul = text.find('\0');
    std::string file = path;
    if (nul != std::string::npos) {
      std::istringstream lines(text.substr(nul + 1));
      for (std::string line; std::getline(lines, line);) overrides.push_back(line);
      file = path + ".yaml";
      std::ofstream(file) << text.substr(0, nul);
    }
    std::string why;
    try {
      const node::ParamSource source = eval::yamlParamSource(file, overrides);
      const std::string name = fs::path(path).filename().string();
      if (name.rfind("matcher", 0) == 0) why = loads(&node::loadMatcherOptions, source);
      if (name == "ekf.yaml") why = loads(&node::loadEkfNodeOptions, source);
      if (name == "map_server.yaml") why = loads(&node::loadRasterOptions, source);
      if (name == "cloud_merger.yaml") why = loads(&node::loadCloudMergerOptions, source);
    } catch (const node::ConfigError& e) {
      why = e.what();
    }
    if (file != path) fs::remove(file);
    return why;
  }
  return "unknown target";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: fuzz_make_seeds OUT_DIR CONFIG_DIR\n";
    return 2;
  }
  g_out = argv[1];
  std::vector<TileInfo> infos;
  mapSeeds(infos);
  rasterSeeds();
  cloudSeeds();
  pcdSeeds();
  kittiSeeds();
  yamlSeeds(argv[2]);
  std::cout << "fuzz_make_seeds: " << g_count << " seeds in " << g_out << "\n";
  return 0;
}
