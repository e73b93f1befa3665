// build_map's rosbag input, its command line and the synthetic street (the PCD input is tested
// in build_map_pcd_test.cpp). No ROS master is needed (rosbag files are written and read directly).
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include <gtest/gtest.h>

#include "../../unit/support/temp_dir.h"
#include "build_map/build_map_options.h"
#include "build_map/build_map_readers.h"
#include "build_map/build_map_synthetic.h"
#include "gmm_localization/core/map/map_format.h"
#include "ouster_cloud.h"

namespace gmm_localization {
namespace tools {
namespace {

using testing::ousterCloud;
using testing::TempDir;

sensor_msgs::PointCloud2 cloudMsg(double t, const std::string& frame, float x) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp.fromSec(t);
  c.header.frame_id = frame;
  c.height = 1;
  c.width = 1;
  c.point_step = 12;
  c.row_step = 12;
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    sensor_msgs::PointField f;
    f.name = names[k];
    f.offset = 4 * k;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
  }
  const float v[3] = {x, 0.f, 0.f};
  c.data.resize(12);
  std::memcpy(c.data.data(), v, 12);
  return c;
}

std::string writeBag(const std::string& dir, bool with_tf) {
  const std::string path = dir + "/drive.bag";
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int i = 0; i <= 10; ++i) {  // 1 m/s along x, 10 Hz, for 1 s
    nav_msgs::Odometry o;
    o.header.stamp.fromSec(100.0 + 0.1 * i);
    o.header.frame_id = "map";
    o.child_frame_id = "base_link";
    o.pose.pose.position.x = 0.1 * i;
    o.pose.pose.orientation.w = 1.0;
    bag.write("/odom", o.header.stamp, o);
  }
  if (with_tf) {
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "base_link";
    t.child_frame_id = "velodyne";
    t.transform.translation.z = 2.0;
    t.transform.rotation.w = 1.0;
    tf.transforms.push_back(t);
    bag.write("/tf_static", ros::Time(100.0), tf);
  }
  bag.write("/points", ros::Time(100.25), cloudMsg(100.25, "velodyne", 1.f));
  auto bad = cloudMsg(100.5, "velodyne", 1.f);
  bad.point_step = 8;  // smaller than the z field's end
  bag.write("/points", ros::Time(100.5), bad);
  bag.write("/points", ros::Time(100.55), cloudMsg(100.55, "velodyne", 2.f));
  bag.write("/points", ros::Time(101.5), cloudMsg(101.5, "velodyne", 1.f));  // after the poses
  bag.close();
  return path;
}

TEST(RosbagSource, InterpolatesPosesAppliesTfStaticAndSkipsWhatItCannotPlace) {
  TempDir dir("gmm_readers");
  RosbagSourceOptions o;
  o.path = writeBag(dir.path, true);
  o.cloud_topic = "/points";
  o.pose_topic = "/odom";
  auto src = RosbagSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  EXPECT_EQ((*src)->sizeHint(), 4u);
  PointBatch b;
  auto more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more) << more.error();
  ASSERT_EQ(b.points_m.size(), 1u);
  EXPECT_TRUE(b.has_sensor_origin);
  EXPECT_NEAR(b.sensor_origin_m.x(), 0.25, 1e-6);  // interpolated at the cloud's stamp
  EXPECT_NEAR(b.sensor_origin_m.z(), 2.0, 1e-6);   // base_link -> velodyne from /tf_static
  EXPECT_NEAR(b.points_m[0].x(), 1.25, 1e-5);
  more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more);
  EXPECT_NEAR(b.points_m[0].x(), 2.55, 1e-5);
  more = (*src)->next(b);
  ASSERT_TRUE(more.ok());
  EXPECT_FALSE(*more);
  const std::string skipped = (*src)->skipped();
  EXPECT_NE(skipped.find("1 outside the poses' time span"), std::string::npos) << skipped;
  // The matcher's reader's reason (cloud_conversion.h).
  EXPECT_NE(skipped.find("1 malformed (last: field 'z' (offset 8) does not fit in point_step 8)"),
            std::string::npos)
      << skipped;
  EXPECT_NE(skipped.find("0 deskewed, 2 without per-point times"), std::string::npos) << skipped;
}

TEST(RosbagSource, FailsClearlyWithoutExtrinsicAndUsesAGivenOne) {
  TempDir dir("gmm_readers");
  RosbagSourceOptions o;
  o.path = writeBag(dir.path, false);
  o.cloud_topic = "/points";
  o.pose_topic = "/odom";
  auto src = RosbagSource::open(o);
  ASSERT_TRUE(src.ok());
  PointBatch b;
  auto more = (*src)->next(b);
  ASSERT_FALSE(more.ok());
  EXPECT_NE(more.error().find("'velodyne'"), std::string::npos) << more.error();
  EXPECT_NE(more.error().find("--extrinsic"), std::string::npos);
  o.has_extrinsic = true;
  o.pose_T_cloud.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
  auto src2 = RosbagSource::open(o);
  ASSERT_TRUE(src2.ok());
  more = (*src2)->next(b);
  ASSERT_TRUE(more.ok() && *more);
  EXPECT_NEAR(b.sensor_origin_m.z(), 1.0, 1e-9);
  o.pose_topic = "/points";  // wrong type on the pose topic
  auto wrong = RosbagSource::open(o);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().find("sensor_msgs/PointCloud2"), std::string::npos) << wrong.error();
  o.path = dir.path + "/missing.bag";
  EXPECT_FALSE(RosbagSource::open(o).ok());
}

TEST(RosbagSource, DeskewsWithPerPointTime) {
  TempDir dir("gmm_readers");
  const std::string path = dir.path + "/timed.bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (int i = 0; i <= 10; ++i) {  // 1 m/s along x
      nav_msgs::Odometry o;
      o.header.stamp.fromSec(100.0 + 0.1 * i);
      o.child_frame_id = "base_link";
      o.pose.pose.position.x = 0.1 * i;
      o.pose.pose.orientation.w = 1.0;
      bag.write("/odom", o.header.stamp, o);
    }
    sensor_msgs::PointCloud2 c = cloudMsg(100.2, "base_link", 1.f);
    sensor_msgs::PointField f;
    f.name = "time";
    f.offset = 12;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
    c.width = 2;
    c.point_step = 16;
    c.row_step = 32;
    const float v[8] = {1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.1f};  // the same point, 0.1 s later
    c.data.resize(32);
    std::memcpy(c.data.data(), v, 32);
    bag.write("/points", ros::Time(100.2), c);
  }
  RosbagSourceOptions o;
  o.path = path;
  o.cloud_topic = "/points";
  o.pose_topic = "/odom";
  for (bool deskew : {true, false}) {
    o.deskew = deskew;
    auto src = RosbagSource::open(o);
    ASSERT_TRUE(src.ok()) << src.error();
    PointBatch b;
    auto more = (*src)->next(b);
    ASSERT_TRUE(more.ok() && *more) << more.error();
    ASSERT_EQ(b.points_m.size(), 2u);
    EXPECT_NEAR(b.points_m[0].x(), 1.2, 1e-5);
    EXPECT_NEAR(b.points_m[1].x(), deskew ? 1.3 : 1.2, 1e-5);
    EXPECT_NEAR(b.sensor_origin_m.x(), 0.2, 1e-9);
  }
}

geometry_msgs::TransformStamped transform(double stamp, const std::string& parent,
                                          const std::string& child, const Eigen::Vector3d& t,
                                          double yaw = 0.0) {
  geometry_msgs::TransformStamped m;
  m.header.stamp.fromSec(stamp);
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = t.x();
  m.transform.translation.y = t.y();
  m.transform.translation.z = t.z();
  m.transform.rotation.z = std::sin(yaw / 2);
  m.transform.rotation.w = std::cos(yaw / 2);
  return m;
}

/// A drive without a pose topic: /tf has map -> odom (2 Hz, y = 10 m) and odom -> base_link
/// (20 Hz, 2 m/s along x, x = 0 at t = 100 s) from 100 to 101 s; /tf_static has the two-edge
/// chain base_link -> mount (z 1.5 m) -> os_sensor (x 0.5 m, yaw 90 deg).
void writeTfDrive(rosbag::Bag& bag) {
  for (int i = 0; i <= 2; ++i) {
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(transform(100.0 + 0.5 * i, "map", "odom", {0.0, 10.0, 0.0}));
    bag.write("/tf", ros::Time(100.0 + 0.5 * i), tf);
  }
  for (int i = 0; i <= 20; ++i) {
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(transform(100.0 + 0.05 * i, "odom", "base_link", {0.1 * i, 0.0, 0.0}));
    bag.write("/tf", ros::Time(100.0 + 0.05 * i), tf);
  }
  tf2_msgs::TFMessage st;
  st.transforms.push_back(transform(100.0, "base_link", "mount", {0.0, 0.0, 1.5}));
  st.transforms.push_back(transform(100.0, "mount", "os_sensor", {0.5, 0.0, 0.0}, M_PI / 2));
  bag.write("/tf_static", ros::Time(100.0), st);
}

TEST(RosbagSource, OusterTimesTfStaticChainAndPosesFromTf) {
  TempDir dir("gmm_readers");
  const std::string path = dir.path + "/ouster.bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    writeTfDrive(bag);
    // The same sensor point twice, the second 50 ms later.
    bag.write("/os_cloud", ros::Time(100.25),
              ousterCloud(100.25, "os_sensor", {{1.f, 0.f, 0.f}, {1.f, 0.f, 0.f}}, {0, 50000000}));
    // Hesai-like absolute times on another clock: not deskewed, counted.
    sensor_msgs::PointCloud2 c = cloudMsg(100.5, "os_sensor", 1.f);
    sensor_msgs::PointField f;
    f.name = "timestamp";
    f.offset = 12;
    f.datatype = sensor_msgs::PointField::FLOAT64;
    f.count = 1;
    c.fields.push_back(f);
    c.point_step = c.row_step = 20;
    c.data.resize(20);
    const double since_boot = 1234.5;
    std::memcpy(c.data.data() + 12, &since_boot, 8);
    bag.write("/os_cloud", ros::Time(100.5), c);
  }
  RosbagSourceOptions o;
  o.path = path;
  o.cloud_topic = "/os_cloud";
  o.pose_tf_parent = "map";
  o.pose_tf_child = "base_link";
  auto src = RosbagSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  EXPECT_NE((*src)->describe().find("poses of map -> base_link from /tf"), std::string::npos)
      << (*src)->describe();
  PointBatch b;
  auto more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more) << more.error();
  ASSERT_EQ(b.points_m.size(), 2u);
  // Sensor (1, 0, 0) -> mount (0.5, 1, 0) -> base_link (0.5, 1, 1.5); base_link at the stamp is
  // at (0.5, 10, 0) in map (map -> odom -> base_link), 0.1 m further 50 ms later.
  EXPECT_NEAR(b.sensor_origin_m.x(), 1.0, 1e-6);
  EXPECT_NEAR(b.sensor_origin_m.y(), 10.0, 1e-6);
  EXPECT_NEAR(b.sensor_origin_m.z(), 1.5, 1e-6);
  EXPECT_NEAR(b.points_m[0].x(), 1.0, 1e-5);
  EXPECT_NEAR(b.points_m[0].y(), 11.0, 1e-5);
  EXPECT_NEAR(b.points_m[0].z(), 1.5, 1e-5);
  EXPECT_NEAR(b.points_m[1].x(), 1.1, 1e-5);  // deskewed with Ouster's `t`
  EXPECT_NEAR(b.points_m[1].y(), 11.0, 1e-5);
  more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more) << more.error();
  ASSERT_EQ(b.points_m.size(), 1u);
  EXPECT_NEAR(b.points_m[0].x(), 1.5, 1e-5);  // base_link at (1, 10, 0): (1.5, 11, 1.5)
  EXPECT_NEAR(b.points_m[0].y(), 11.0, 1e-5);
  more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && !*more);
  const std::string skipped = (*src)->skipped();
  EXPECT_NE(skipped.find("1 deskewed (per-point 't' uint32 relative nanoseconds)"),
            std::string::npos)
      << skipped;
  EXPECT_NE(skipped.find("1 with times that make no sense (last: per-point 'timestamp'"),
            std::string::npos)
      << skipped;

  // A frame pair that /tf does not connect: the error lists what it has.
  o.pose_tf_child = "wheel";
  auto bad = RosbagSource::open(o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("no transform map -> wheel in /tf"), std::string::npos) << bad.error();
  EXPECT_NE(bad.error().find("odom -> base_link"), std::string::npos) << bad.error();
  // The default pose topic is absent: the error points to --pose-tf.
  o.pose_tf_parent.clear();
  o.pose_tf_child.clear();
  bad = RosbagSource::open(o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("--pose-tf"), std::string::npos) << bad.error();
  // Odometry of base_link and the cloud two static edges away: the chain is composed.
  const std::string odom_path = dir.path + "/odom.bag";
  {
    rosbag::Bag bag(odom_path, rosbag::bagmode::Write);
    writeTfDrive(bag);
    for (int i = 0; i <= 10; ++i) {
      nav_msgs::Odometry od;
      od.header.stamp.fromSec(100.0 + 0.1 * i);
      od.child_frame_id = "base_link";
      od.pose.pose.position.x = 0.2 * i;
      od.pose.pose.orientation.w = 1.0;
      bag.write("/odom", od.header.stamp, od);
    }
    bag.write("/os_cloud", ros::Time(100.25),
              ousterCloud(100.25, "os_sensor", {{1.f, 0.f, 0.f}}, {0}));
  }
  o.path = odom_path;
  o.pose_topic = "/odom";
  src = RosbagSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  more = (*src)->next(b);
  ASSERT_TRUE(more.ok() && *more) << more.error();
  EXPECT_NEAR(b.points_m[0].x(), 1.0, 1e-5);
  EXPECT_NEAR(b.points_m[0].y(), 1.0, 1e-5);
  EXPECT_NEAR(b.points_m[0].z(), 1.5, 1e-5);
}

TEST(BuildMapArgs, ParsesAndRejects) {
  const char* ok[] = {"build_map", "--output", "/tmp/m",   "--kitti", "/data",
                      "--scans",   "0,2,4-5",  "--k-max",  "3",       "--blur-sigma",
                      "0.15",      "--offset", "100,200,3"};
  auto c = parseBuildMapArgs(13, const_cast<char**>(ok));
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->input, InputKind::kKitti);
  EXPECT_EQ(c->kitti.scans, (std::vector<int>{0, 2, 4, 5}));
  EXPECT_EQ(c->builder.em.max_components, 3);
  EXPECT_DOUBLE_EQ(c->builder.blur_sigma_m, 0.15);
  EXPECT_TRUE(c->builder.georeference.present);
  EXPECT_DOUBLE_EQ(c->builder.georeference.origin_northing_m, 200.0);
  const char* two[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--kitti", "d"};
  EXPECT_NE(parseBuildMapArgs(7, const_cast<char**>(two)).error().find("exactly one input"),
            std::string::npos);
  const char* bad[] = {"build_map", "--output", "/tmp/m", "--pcd", "a.pcd", "--k-max", "5"};
  EXPECT_NE(parseBuildMapArgs(7, const_cast<char**>(bad)).error().find("max_components"),
            std::string::npos);
  const char* tf[] = {"build_map", "--output",  "/tmp/m",       "--bag",
                      "a.bag",     "--pose-tf", "map,base_link"};
  c = parseBuildMapArgs(7, const_cast<char**>(tf));
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->bag.pose_tf_parent, "map");
  EXPECT_EQ(c->bag.pose_tf_child, "base_link");
  EXPECT_EQ(c->bag.time_field, "");  // any time field the reader knows
  const char* tf_bad[] = {"build_map", "--output", "/tmp/m", "--bag", "a.bag", "--pose-tf", "map"};
  EXPECT_NE(parseBuildMapArgs(7, const_cast<char**>(tf_bad)).error().find("PARENT,CHILD"),
            std::string::npos);
  const char* both[] = {"build_map", "--output",      "/tmp/m",       "--bag", "a.bag",
                        "--pose-tf", "map,base_link", "--pose-topic", "/odom"};
  EXPECT_NE(parseBuildMapArgs(9, const_cast<char**>(both)).error().find("one source of poses"),
            std::string::npos);
  const char* unknown[] = {"build_map", "--frobnicate"};
  EXPECT_NE(parseBuildMapArgs(2, const_cast<char**>(unknown)).error().find("unknown option"),
            std::string::npos);
  auto t = parseTransform("--extrinsic", "1,2,3,0,0,90");
  ASSERT_TRUE(t.ok());
  EXPECT_NEAR((t->linear() * Eigen::Vector3d::UnitX()).y(), 1.0, 1e-12);
  EXPECT_FALSE(parseTransform("--extrinsic", "1,2,x").ok());
}

TEST(BuildMapArgs, ResolutionIsBoundedByTheMapFormat) {
  // The manifest reader refuses cells outside [kMinMapResolutionM, kMaxMapResolutionM]: the
  // command line must refuse them before a build that could never be served.
  auto parse = [](const std::string& resolution) {
    const char* argv[] = {"build_map", "--output",     "/tmp/m",          "--pcd",
                          "a.pcd",     "--resolution", resolution.c_str()};
    return parseBuildMapArgs(7, const_cast<char**>(argv));
  };
  for (const char* bad : {"5e-4", "0.0499", "10.5", "0", "-0.2", "1e300"}) {
    auto c = parse(bad);
    ASSERT_FALSE(c.ok()) << bad;
    EXPECT_NE(c.error().find("--resolution"), std::string::npos) << c.error();
    EXPECT_NE(c.error().find("[0.05, 10] m"), std::string::npos) << c.error();
  }
  for (double good : {kMinMapResolutionM, 0.2, kMaxMapResolutionM}) {
    std::ostringstream text;
    text.precision(17);
    text << good;
    auto c = parse(text.str());
    ASSERT_TRUE(c.ok()) << good << ": " << c.error();
    EXPECT_EQ(c->builder.geometry.resolution_m, good);
    EXPECT_TRUE(checkMapGeometryBounds(c->builder.geometry).empty()) << "the format accepts it";
  }
}

TEST(SyntheticStreet, DeterministicLidarLikeScans) {
  SyntheticStreetOptions o;
  o.length_m = 50.0;
  o.azimuth_step_deg = 1.0;
  SyntheticStreetSource a(o), b(o);
  EXPECT_EQ(a.sizeHint(), 51u);
  PointBatch pa, pb;
  ASSERT_TRUE(*a.next(pa));
  ASSERT_TRUE(*b.next(pb));
  ASSERT_EQ(pa.points_m.size(), pb.points_m.size());
  EXPECT_GT(pa.points_m.size(), 32u * 360 / 2);  // most rays return
  for (size_t i = 0; i < pa.points_m.size(); ++i) ASSERT_EQ(pa.points_m[i], pb.points_m[i]);
  EXPECT_TRUE(pa.has_sensor_origin);
  size_t ground = 0;
  for (const auto& p : pa.points_m) {
    const double r = (p.cast<double>() - pa.sensor_origin_m).norm();
    EXPECT_LE(r, 100.2);
    ground += std::abs(p.z()) < 0.2;
  }
  EXPECT_GT(ground, pa.points_m.size() / 4);
}

}  // namespace
}  // namespace tools
}  // namespace gmm_localization
