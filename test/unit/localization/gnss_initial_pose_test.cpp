// GNSS initial pose: synthetic ground truth (a base_link pose in a georeferenced map, the
// antenna on a lever arm), fixes made from it with mapToGeodetic, the pose recovered.
#include "gmm_localization/core/localization/gnss_initial_pose.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "support/test_georeference.h"

namespace gmm_localization {
namespace {

Georeference georeference() { return testing::simulatorGeoreference(); }

const Eigen::Vector3d kLever(0.8, -0.3, 1.6);  // antenna in base_link

/// The fix of an antenna on kLever of base_link at (x, y, z, yaw) in the map.
GnssFix fixAt(double stamp, double x, double y, double z, double yaw, double sigma = 0.02) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  auto geo = mapToGeodetic(georeference(), x + c * kLever.x() - s * kLever.y(),
                           y + s * kLever.x() + c * kLever.y(), z + kLever.z());
  EXPECT_TRUE(geo.ok());
  GnssFix f;
  f.stamp_s = stamp;
  f.position = *geo;
  f.east_var_m2 = f.north_var_m2 = sigma * sigma;
  f.up_var_m2 = 4 * sigma * sigma;
  return f;
}

/// ENU yaw of a map-frame yaw at a map point: map yaw - convergence.
double enuYaw(double x, double y, double map_yaw) {
  const Georeference g = georeference();
  auto geo = mapToGeodetic(g, x, y, 0.0);
  auto p = geodeticToMap(g, *geo);
  return map_yaw - p->convergence_rad;
}

GnssInitialPoseOptions options() {
  GnssInitialPoseOptions o;
  o.antenna_in_base = kLever;
  return o;
}

TEST(GnssInitialPose, HeadingTopicGivesThePose) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-20000.0, 20000.0), ang(-M_PI, M_PI);
  for (int trial = 0; trial < 20; ++trial) {
    const double x = pos(rng), y = pos(rng), z = 3.0, yaw = ang(rng);
    GnssInitialPose init(options());
    ASSERT_TRUE(init.addHeading({100.0, enuYaw(x, y, yaw), 0.01}));
    auto e = init.addFix(georeference(), fixAt(100.2, x, y, z, yaw));
    ASSERT_TRUE(e.ok()) << e.error();
    EXPECT_NEAR(e->x_m, x, 1e-4);
    EXPECT_NEAR(e->y_m, y, 1e-4);
    EXPECT_NEAR(e->z_m, z, 1e-6);
    EXPECT_NEAR(std::remainder(e->yaw_rad - yaw, 2 * M_PI), 0.0, 1e-6);
    EXPECT_EQ(e->heading_source, "heading topic");
    EXPECT_NEAR(e->cov_xy_yaw(2, 2), 1e-4, 1e-12);
    // 2 cm fix, floored at min_sigma_m.
    EXPECT_NEAR(e->cov_xy_yaw(0, 0), 0.02 * 0.02 + 0.3 * 0.3, 1e-9);
    EXPECT_DOUBLE_EQ(e->stamp_s, 100.2);
  }
}

TEST(GnssInitialPose, CourseOverGroundAfterEnoughDistance) {
  GnssInitialPose init(options());
  const double yaw = 0.7;
  int waited = 0;
  Result<GnssPoseEstimate> e = Result<GnssPoseEstimate>::failure("none");
  for (int k = 0; k < 20; ++k) {
    const double d = 1.0 * k;  // 10 m/s at 10 Hz
    e = init.addFix(georeference(),
                    fixAt(10.0 + 0.1 * k, 100 + d * std::cos(yaw), 50 + d * std::sin(yaw), 0, yaw));
    if (e.ok()) break;
    ++waited;
    EXPECT_NE(e.error().find("waiting for a heading"), std::string::npos) << e.error();
  }
  ASSERT_TRUE(e.ok()) << e.error();
  EXPECT_EQ(waited, 8) << "course_min_distance_m is 8 m";
  EXPECT_EQ(e->heading_source, "course over ground");
  EXPECT_NEAR(e->yaw_rad, yaw, 1e-6);
  EXPECT_NEAR(e->x_m, 100 + 8 * std::cos(yaw), 1e-4);
  EXPECT_GT(e->cov_xy_yaw(2, 2), 0.1 * 0.1);
}

TEST(GnssInitialPose, OldHeadingAndGapsAreNotUsed) {
  GnssInitialPose init(options());
  init.addHeading({0.0, 1.0, 0.01});
  auto e = init.addFix(georeference(), fixAt(5.0, 0, 0, 0, 1.0));
  ASSERT_FALSE(e.ok()) << "a heading 5 s old is not used";
  // Fixes 20 s apart do not make a course (course_max_gap_s 10 s).
  e = init.addFix(georeference(), fixAt(25.0, 30, 0, 0, 0.0));
  EXPECT_FALSE(e.ok());
  e = init.addFix(georeference(), fixAt(26.0, 40, 0, 0, 0.0));
  ASSERT_TRUE(e.ok()) << e.error();
  EXPECT_NEAR(e->yaw_rad, 0.0, 1e-6);
}

TEST(GnssInitialPose, RefusesWithReasons) {
  GnssInitialPose init(options());
  init.addHeading({1.0, 0.0, NAN});
  auto expectRefused = [&](const Georeference& g, const GnssFix& f, const char* words) {
    auto e = init.addFix(g, f);
    ASSERT_FALSE(e.ok());
    EXPECT_NE(e.error().find(words), std::string::npos) << e.error();
  };
  expectRefused(Georeference(), fixAt(1.0, 0, 0, 0, 0), "no georeference");
  Georeference text = georeference();
  text.utm_zone = 0;
  text.datum = "local";
  expectRefused(text, fixAt(1.0, 0, 0, 0, 0), "names no UTM zone");
  GnssFix f = fixAt(1.0, 0, 0, 0, 0);
  f.has_solution = false;
  expectRefused(georeference(), f, "no fix");
  expectRefused(georeference(), fixAt(1.0, 0, 0, 0, 0, 25.0), "too coarse");
  expectRefused(georeference(), fixAt(1.0, 2e5, 0, 0, 0), "from the map origin");
  f = fixAt(1.0, 0, 0, 0, 0);
  f.position.latitude_deg = NAN;
  expectRefused(georeference(), f, "not finite");
  EXPECT_FALSE(init.addHeading({1.0, NAN, 0.1}));
  // A fix without covariance is taken as unknown_sigma_m, and the heading's unknown sigma as
  // default_heading_sigma_rad.
  f = fixAt(1.0, 0, 0, 0, 0);
  f.east_var_m2 = f.north_var_m2 = NAN;
  auto e = init.addFix(georeference(), f);
  ASSERT_TRUE(e.ok()) << e.error();
  EXPECT_NEAR(e->cov_xy_yaw(0, 0), 3.0 * 3.0 + 0.3 * 0.3, 1e-9);
  EXPECT_NEAR(e->cov_xy_yaw(2, 2), 0.05 * 0.05, 1e-12);
}

TEST(GnssInitialPose, OptionsValidate) {
  EXPECT_EQ(options().validate(), "");
  GnssInitialPoseOptions o = options();
  o.course_min_distance_m = 0.0;
  EXPECT_NE(o.validate().find("course_min_distance_m"), std::string::npos);
  o = options();
  o.antenna_in_base.x() = NAN;
  EXPECT_NE(o.validate().find("antenna_in_base"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
