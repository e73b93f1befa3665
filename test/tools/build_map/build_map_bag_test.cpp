// build_map --bag end to end, on a bag as an Ouster driver and a localization stack without a
// pose topic record it: Ouster clouds (uint32 `t` in ns after the stamp), the sensor two static
// edges from base_link on /tf_static, the poses only on /tf (map -> odom -> base_link). The tool
// runs as a child process; the map it writes must open, verify and hold the scanned wall and
// ground where they are, and its summary must say that every scan was deskewed.
#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "../../unit/support/temp_dir.h"
#include "gmm_localization/core/map/map_store.h"
#include "ouster_cloud.h"

#ifndef GMM_BUILD_MAP_BINARY
#error "GMM_BUILD_MAP_BINARY (the path of the build_map executable) must be defined"
#endif

namespace gmm_localization {
namespace {

using testing::TempDir;

constexpr double kT0 = 100.0;      // first stamp [s]
constexpr double kSpeed = 2.0;     // along map x [m/s]
constexpr double kMapOdomY = 5.0;  // map -> odom [m]

geometry_msgs::TransformStamped transform(double stamp, const std::string& parent,
                                          const std::string& child, const Eigen::Isometry3d& T) {
  geometry_msgs::TransformStamped m;
  m.header.stamp.fromSec(stamp);
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = T.translation().x();
  m.transform.translation.y = T.translation().y();
  m.transform.translation.z = T.translation().z();
  const Eigen::Quaterniond q(T.linear());
  m.transform.rotation.x = q.x();
  m.transform.rotation.y = q.y();
  m.transform.rotation.z = q.z();
  m.transform.rotation.w = q.w();
  return m;
}

Eigen::Isometry3d odomTBase(double t) {
  return Eigen::Isometry3d(Eigen::Translation3d(kSpeed * (t - kT0), 0.0, 0.0));
}
Eigen::Isometry3d mapTOdom() { return Eigen::Isometry3d(Eigen::Translation3d(0, kMapOdomY, 0)); }
Eigen::Isometry3d baseTMount() { return Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1.8)); }
Eigen::Isometry3d mountTSensor() {
  return Eigen::Translation3d(0.3, 0.0, 0.0) *
         Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
}

/// An Ouster cloud (ouster_ros's layout, uint32 `t` at offset 20) of map points seen over the
/// 0.1 s after `stamp`: each point is written in the sensor frame at its own time, 1 ms
/// resolution, so only deskewing puts it back where it is.
sensor_msgs::PointCloud2 ousterScan(double stamp, const std::vector<Eigen::Vector3d>& world) {
  std::vector<Eigen::Vector3f> points;
  std::vector<uint32_t> t_ns;
  for (size_t i = 0; i < world.size(); ++i) {
    t_ns.push_back(static_cast<uint32_t>((i % 100) * 1000000));  // 0 .. 99 ms
    const double t = stamp + t_ns.back() * 1e-9;
    const Eigen::Isometry3d mapTSensor = mapTOdom() * odomTBase(t) * baseTMount() * mountTSensor();
    points.push_back((mapTSensor.inverse() * world[i]).cast<float>());
  }
  return testing::ousterCloud(stamp, "os_sensor", points, t_ns);
}

/// Map y of the wall: a cell centre (0.2 m cells), so that no point lies on a cell border.
constexpr double kWallY = kMapOdomY + 6.1;

/// A wall at map y = kWallY (x in [-4, 16], z in [0.2, 3]) and ground (z = 0) between it and
/// the road, as map points.
std::vector<Eigen::Vector3d> scene() {
  std::vector<Eigen::Vector3d> w;
  for (int ix = 0; ix <= 200; ++ix) {
    const double x = -3.95 + 0.1 * ix;
    for (int iz = 0; iz <= 28; ++iz) w.emplace_back(x, kWallY, 0.2 + 0.1 * iz);
    for (int iy = 0; iy < 40; ++iy) w.emplace_back(x, kMapOdomY + 2.05 + 0.1 * iy, 0.0);
  }
  return w;
}

std::string writeBag(const std::string& dir) {
  const std::string path = dir + "/ouster_tf.bag";
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int i = 0; i <= 4; ++i) {  // map -> odom at 2 Hz
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(transform(kT0 + 0.5 * i, "map", "odom", mapTOdom()));
    bag.write("/tf", ros::Time(kT0 + 0.5 * i), tf);
  }
  for (int i = 0; i <= 40; ++i) {  // odom -> base_link at 20 Hz
    const double t = kT0 + 0.05 * i;
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(transform(t, "odom", "base_link", odomTBase(t)));
    bag.write("/tf", ros::Time(t), tf);
  }
  tf2_msgs::TFMessage st;
  st.transforms.push_back(transform(kT0, "base_link", "os_mount", baseTMount()));
  st.transforms.push_back(transform(kT0, "os_mount", "os_sensor", mountTSensor()));
  bag.write("/tf_static", ros::Time(kT0), st);
  const std::vector<Eigen::Vector3d> world = scene();
  for (int i = 0; i < 19; ++i) {  // 10 Hz, every revolution inside the poses' span
    const double t = kT0 + 0.05 + 0.1 * i;
    bag.write("/os_cloud", ros::Time(t), ousterScan(t, world));
  }
  bag.close();
  return path;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(BuildMapBag, OusterCloudsTfStaticChainAndPosesFromTfBuildAMap) {
  TempDir dir("gmm_build_map_bag");
  const std::string bag = writeBag(dir.path);
  const std::string map = dir.path + "/map";
  const std::string log = dir.path + "/build_map.log";
  const std::string cmd = std::string(GMM_BUILD_MAP_BINARY) + " --bag " + bag +
                          " --cloud-topic /os_cloud --pose-tf map,base_link --tile-size 64" +
                          " --output " + map + " --quiet > " + log + " 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = readFile(log);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("19 deskewed (per-point 't' uint32 relative nanoseconds)"), std::string::npos)
      << out;
  EXPECT_NE(out.find("0 without per-point times, 0 with times that make no sense"),
            std::string::npos)
      << out;

  auto store = MapStore::open(map);
  ASSERT_TRUE(store.ok()) << store.error();
  auto all = store->loadAll();
  ASSERT_TRUE(all.ok()) << all.error();
  const MapGeometry& g = all->geometry();
  // The wall's cells hold mixtures (undeskewed, a revolution would smear it over 0.2 m of the
  // vehicle's path, and a wrong extrinsic would put it elsewhere), ground at z = 0 lies in front
  // of it and nothing behind it.
  for (double x : {0.1, 6.1, 12.1}) {
    const GaussianMixture1D* wall = all->cell(g.cellAt(x, kWallY));
    ASSERT_NE(wall, nullptr) << x;
    ASSERT_FALSE(wall->empty()) << x;
    const GaussianMixture1D* ground = all->cell(g.cellAt(x, kMapOdomY + 4.1));
    ASSERT_NE(ground, nullptr) << x;
    ASSERT_EQ(ground->size(), 1) << x;
    EXPECT_NEAR(ground->component(0).mean_m, 0.0, 0.05) << x;
    const GaussianMixture1D* behind = all->cell(g.cellAt(x, kWallY + 1.0));
    EXPECT_TRUE(behind == nullptr || behind->empty()) << x;
  }
  // The scene starts at x = -3.95. Undeskewed, a point seen dt after the stamp would land
  // 2 m/s * dt short of it, up to 0.2 m: into the cells before x = -4.
  auto has_data = [&](double x, double y) {
    const GaussianMixture1D* c = all->cell(g.cellAt(x, y));
    return c != nullptr && !c->empty();
  };
  for (double y : {kWallY, kMapOdomY + 4.1}) {
    EXPECT_TRUE(has_data(-3.9, y)) << y;
    EXPECT_FALSE(has_data(-4.1, y)) << y;
  }
}

}  // namespace
}  // namespace gmm_localization
