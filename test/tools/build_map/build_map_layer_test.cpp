// build_map's reflectivity layer (--layer reflectivity): the readers' intensities and vehicle
// origins (PCD, rosbag, synthetic street), the command line's refusals, and build_map and
// map_info run as child processes on a tiny KITTI directory of a painted road.
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "../../unit/support/temp_dir.h"
#include "build_map/build_map_options.h"
#include "build_map/build_map_readers.h"
#include "build_map/build_map_synthetic.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/ros/cloud_conversion.h"

#ifndef GMM_BUILD_MAP_BINARY
#error "GMM_BUILD_MAP_BINARY (the path of the build_map executable) must be defined"
#endif
#ifndef GMM_MAP_INFO_BINARY
#error "GMM_MAP_INFO_BINARY (the path of the map_info executable) must be defined"
#endif

namespace gmm_localization {
namespace tools {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::string readText(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Runs `command` with stdout and stderr into `log`; the exit code (-1 when it did not exit).
int run(const std::string& command, const std::string& log) {
  const int status = std::system((command + " >" + log + " 2>&1 </dev/null").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

Result<BuildMapConfig> parse(std::vector<std::string> args) {
  args.insert(args.begin(), "build_map");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(&a[0]);
  return parseBuildMapArgs(static_cast<int>(argv.size()), argv.data());
}

void writeFloats(std::ofstream& f, std::initializer_list<float> values) {
  for (float v : values) f.write(reinterpret_cast<const char*>(&v), 4);  // little-endian host
}

/// A painted road seen by 5 scans from base_link on the ground (KITTI layout, xyzi records in
/// the scans' frame, poses 1 m apart along x): asphalt 11 with a 1 m stripe of 110 at map
/// y in [1.5, 2.5], and a wall of 60 at map x = 10 from 0.5 to 3 m (not ground).
void writeKittiRoad(const std::string& dir) {
  fs::create_directories(dir + "/velodyne");
  std::ofstream poses(dir + "/poses.txt");
  for (int i = 0; i < 5; ++i) {
    poses << "1 0 0 " << i << " 0 1 0 0 0 0 1 0\n";
    char name[32];
    std::snprintf(name, sizeof name, "/velodyne/%06d.bin", i);
    std::ofstream scan(dir + name, std::ios::binary);
    for (double x = -7.95; x < 12.0; x += 0.1) {
      for (double y = -7.95; y < 8.0; y += 0.1) {
        const float paint = std::abs(y - 2.0) < 0.5 ? 110.f : 11.f;
        writeFloats(scan, {float(x - i), float(y), 0.f, paint});
      }
    }
    for (double y = -3.95; y < 4.0; y += 0.1)
      for (double z = 0.55; z < 3.0; z += 0.1)
        writeFloats(scan, {float(10.0 - i), float(y), float(z), 60.f});
  }
}

TEST(BuildMapLayer, ReflectivityMapOfATinyKittiDirectory) {
  TempDir work("gmm_build_map_layer");
  const std::string kitti = work.path + "/kitti", map = work.path + "/map";
  writeKittiRoad(kitti);
  const std::string log = work.path + "/build.log";
  const int code = run(std::string(GMM_BUILD_MAP_BINARY) + " --kitti " + kitti +
                           " --kitti-fields xyzi --layer reflectivity --output " + map +
                           "/reflectivity --tile-size 64 --quiet",
                       log);
  const std::string out = readText(log);
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("layer            reflectivity (value = intensity x 0.02 m"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("as ground returns"), std::string::npos) << out;
  EXPECT_NE(out.find(" not ground, "), std::string::npos) << out;

  const std::string info_log = work.path + "/info.log";
  ASSERT_EQ(run(std::string(GMM_MAP_INFO_BINARY) + " " + map + "/reflectivity", info_log), 0)
      << readText(info_log);
  const std::string info = readText(info_log);
  EXPECT_NE(info.find("(format version 3)"), std::string::npos) << info;
  EXPECT_NE(info.find("layer            reflectivity (value = intensity x 0.02 m; ground: "
                      "[-0.3, 0.3] m around z = 0 m of the vehicle frame, within 40 m)"),
            std::string::npos)
      << info;

  auto store = MapStore::open(map + "/reflectivity");
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->layer(), MapLayer::kReflectivity);
  auto all = store->loadAll();
  ASSERT_TRUE(all.ok()) << all.error();
  auto cell = [&](double x, double y) {
    const GaussianMixture1D* g = all->cell(all->geometry().cellAt(x, y));
    return g ? *g : GaussianMixture1D();
  };
  ASSERT_EQ(cell(2.1, 2.1).size(), 1);
  EXPECT_NEAR(cell(2.1, 2.1).component(0).mean_m, 2.2, 0.02);  // paint
  ASSERT_EQ(cell(2.1, -3.9).size(), 1);
  EXPECT_NEAR(cell(2.1, -3.9).component(0).mean_m, 0.22, 0.02);  // asphalt
  // The wall stands on asphalt: its cells hold the ground under it only.
  ASSERT_EQ(cell(10.05, 0.1).size(), 1);
  EXPECT_NEAR(cell(10.05, 0.1).component(0).mean_m, 0.22, 0.02);
}

TEST(BuildMapLayer, InputsThatCannotMakeAReflectivityMapAreRefused) {
  auto error = [](const std::vector<std::string>& args) {
    auto c = parse(args);
    return c.ok() ? std::string("accepted") : c.error();
  };
  EXPECT_NE(error({"--pcd", "map.pcd", "--layer", "reflectivity", "--out", "m"})
                .find("a PCD map has no vehicle poses"),
            std::string::npos);
  EXPECT_NE(
      error({"--kitti", "d", "--kitti-fields", "xyz", "--layer", "reflectivity", "--out", "m"})
          .find("--kitti-fields xyz has none"),
      std::string::npos);
  EXPECT_EQ(error({"--kitti", "d", "--ground-band", "-0.2,0.2", "--out", "m"}),
            "--ground-band applies to --layer reflectivity only");
  EXPECT_EQ(
      error({"--kitti", "d", "--layer", "reflectivity", "--ground-band", "0.3,-0.3", "--out", "m"}),
      "invalid options: --ground-band: reflectivity.ground_max_m=-0.3 must exceed "
      "ground_min_m=0.3");
  EXPECT_EQ(error({"--kitti", "d", "--layer", "intensity", "--out", "m"}),
            "--layer: 'intensity' is not height or reflectivity");
  auto c =
      parse({"--kitti", "d", "--layer", "reflectivity", "--ground-height", "-1.73", "--ground-band",
             "-0.2,0.25", "--ground-range", "30", "--reflectivity-scale", "0.01", "--out", "m"});
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->builder.layer, MapLayer::kReflectivity);
  EXPECT_EQ(c->builder.reflectivity.ground_height_m, -1.73);
  EXPECT_EQ(c->builder.reflectivity.ground_min_m, -0.2);
  EXPECT_EQ(c->builder.reflectivity.ground_max_m, 0.25);
  EXPECT_EQ(c->builder.reflectivity.max_range_m, 30.0);
  EXPECT_EQ(c->builder.reflectivity.metres_per_unit, 0.01);
  EXPECT_EQ(parse({"--kitti", "d", "--out", "m"})->builder.layer, MapLayer::kHeight);

  // Scans without intensities found while reading: the reason names the input.
  TempDir work("gmm_build_map_layer");
  fs::create_directories(work.path + "/k/000000");
  std::ofstream(work.path + "/k/graph.txt") << "v0 0 0 0 0 0 0 1\n";
  {
    std::ofstream scan(work.path + "/k/000000/points.bin", std::ios::binary);  // keyframe: xyz
    for (int i = 0; i < 50; ++i) writeFloats(scan, {2.f + 0.1f * i, 0.f, 0.f});
  }
  const std::string log = work.path + "/log";
  EXPECT_EQ(run(std::string(GMM_BUILD_MAP_BINARY) + " --kitti " + work.path +
                    "/k --layer reflectivity --output " + work.path + "/m --quiet",
                log),
            1);
  EXPECT_NE(readText(log).find("KITTI scans '" + work.path + "/k' (1 scans, poses '" + work.path +
                               "/k/graph.txt'): batch 1: no intensity"),
            std::string::npos)
      << readText(log);
  EXPECT_FALSE(fs::exists(work.path + "/m/" + kManifestFileName));
}

/// A PCD file (binary, binary_compressed as LZF literal runs, or ascii) of x y z F4 and
/// intensity U1, one point non-finite.
std::string pcdFile(const std::string& data) {
  const float xyz[3][3] = {{1.f, 2.f, 0.f}, {NAN, 0.f, 0.f}, {3.f, 4.f, 0.1f}};
  const uint8_t intensity[3] = {11, 200, 110};
  std::string out =
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 3\n"
      "HEIGHT 1\nPOINTS 3\nDATA " +
      data + "\n";
  if (data == "ascii") {
    for (int i = 0; i < 3; ++i) {
      out += (std::isnan(xyz[i][0]) ? std::string("nan") : std::to_string(xyz[i][0])) + " " +
             std::to_string(xyz[i][1]) + " " + std::to_string(xyz[i][2]) + " " +
             std::to_string(intensity[i]) + "\n";
    }
    return out;
  }
  std::string bytes;
  auto put = [&](const void* p, size_t n) { bytes.append(static_cast<const char*>(p), n); };
  if (data == "binary") {
    for (int i = 0; i < 3; ++i) {
      put(xyz[i], 12);
      put(&intensity[i], 1);
    }
    return out + bytes;
  }
  for (int k = 0; k < 3; ++k)  // column-wise
    for (int i = 0; i < 3; ++i) put(&xyz[i][k], 4);
  put(intensity, 3);
  std::string lzf;  // literal runs of at most 32 bytes: control byte = length - 1
  for (size_t i = 0; i < bytes.size(); i += 32) {
    const size_t n = std::min<size_t>(32, bytes.size() - i);
    lzf += static_cast<char>(n - 1);
    lzf += bytes.substr(i, n);
  }
  const uint32_t sizes[2] = {static_cast<uint32_t>(lzf.size()),
                             static_cast<uint32_t>(bytes.size())};
  return out + std::string(reinterpret_cast<const char*>(sizes), 8) + lzf;
}

TEST(PcdSource, CarriesTheIntensityFieldAlignedWithTheKeptPoints) {
  TempDir dir("gmm_build_map_layer");
  for (const char* data : {"ascii", "binary", "binary_compressed"}) {
    const std::string path = dir.path + "/" + data + ".pcd";
    std::ofstream(path, std::ios::binary) << pcdFile(data);
    PcdSourceOptions o;
    o.paths = {path};
    auto src = PcdSource::open(o);
    ASSERT_TRUE(src.ok()) << data << ": " << src.error();
    PointBatch b;
    auto more = (*src)->next(b);
    ASSERT_TRUE(more.ok() && *more) << data << ": " << more.error();
    ASSERT_EQ(b.points_m.size(), 2u) << data;  // the non-finite point is dropped ...
    EXPECT_EQ(b.intensity, (std::vector<float>{11.f, 110.f})) << data;  // ... with its intensity
    EXPECT_FALSE(b.has_vehicle_origin) << data;
  }
}

TEST(RosbagSource, CarriesIntensityAndThePosesFrameAsTheVehicle) {
  TempDir dir("gmm_build_map_layer");
  const std::string path = dir.path + "/drive.bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (int i = 0; i <= 2; ++i) {
      nav_msgs::Odometry o;
      o.header.stamp.fromSec(100.0 + 0.1 * i);
      o.header.frame_id = "map";
      o.child_frame_id = "base_link";
      o.pose.pose.position.x = 0.1 * i;
      o.pose.pose.position.z = 0.5;
      o.pose.pose.orientation.w = 1.0;
      bag.write("/odom", o.header.stamp, o);
    }
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "base_link";
    t.child_frame_id = "velodyne";
    t.transform.translation.z = 2.0;
    t.transform.rotation.w = 1.0;
    tf.transforms.push_back(t);
    bag.write("/tf_static", ros::Time(100.0), tf);
    node::CloudData cloud;
    cloud.points = {Eigen::Vector3f(5.f, 0.f, -2.f), Eigen::Vector3f(6.f, 1.f, -2.f)};
    cloud.intensity = {12.f, 105.f};
    sensor_msgs::PointCloud2 msg;
    node::toMsg(cloud, msg);
    msg.header.stamp.fromSec(100.1);
    msg.header.frame_id = "velodyne";
    bag.write("/points", msg.header.stamp, msg);
  }
  RosbagSourceOptions o;
  o.path = path;
  o.cloud_topic = "/points";
  o.pose_topic = "/odom";
  auto src = RosbagSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  PointBatch b;
  auto more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more) << more.error();
  EXPECT_EQ(b.intensity, (std::vector<float>{12.f, 105.f}));
  ASSERT_TRUE(b.has_vehicle_origin);
  EXPECT_TRUE(b.vehicle_origin_m.isApprox(Eigen::Vector3d(0.1, 0.0, 0.5)));  // base_link
  EXPECT_NEAR(b.sensor_origin_m.z(), 2.5, 1e-9);                             // the velodyne
  EXPECT_NEAR(b.points_m[0].z() - b.vehicle_origin_m.z(), 0.0, 1e-6);        // on the ground
}

TEST(SyntheticStreet, IntensitiesOfPaintAsphaltAndFacades) {
  SyntheticStreetOptions o;
  o.length_m = 20.0;
  o.azimuth_step_deg = 0.5;
  SyntheticStreetSource s(o);
  PointBatch b;
  ASSERT_TRUE(*s.next(b));
  ASSERT_TRUE(b.hasIntensity());
  ASSERT_TRUE(b.has_vehicle_origin);
  EXPECT_NEAR(b.sensor_origin_m.z() - b.vehicle_origin_m.z(), 1.95, 1e-9);
  size_t paint = 0, asphalt = 0, facade = 0;
  for (size_t i = 0; i < b.points_m.size(); ++i) {
    const Eigen::Vector3f& p = b.points_m[i];
    const float v = b.intensity[i];
    if (std::abs(p.y()) < 0.05 && std::abs(p.z() - 0.08) < 0.1) paint += v == 110.f;
    if (std::abs(p.y() + 2.0) < 0.5 && std::abs(p.z()) < 0.2) asphalt += v == 11.f;
    if (p.z() > 4.0 && std::abs(p.y()) > 11.0) facade += v == 60.f;
  }
  EXPECT_GT(paint, 5u);  // the centre line
  EXPECT_GT(asphalt, 100u);
  EXPECT_GT(facade, 100u);
}

}  // namespace
}  // namespace tools
}  // namespace gmm_localization
