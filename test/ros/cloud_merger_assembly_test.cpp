// The cloud merger's geometry (cloud_merger_assembly.h): extrinsics applied exactly, non-finite
// points dropped with their fields, times re-based to the set's stamp, fields kept only when
// every input has them.
#include "gmm_localization/ros/cloud_merger_assembly.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

CloudData threePoints() {
  CloudData c;
  c.points = {{1.f, 0.f, 0.f}, {kNan, 0.f, 0.f}, {0.f, 2.f, -1.f}};
  c.time_s = {0.01f, 0.02f, 0.03f};
  c.intensity = {10.f, 20.f, 30.f};
  c.ring = {1, 2, 3};
  c.label = {0, 1, 2};
  return c;
}

Eigen::Isometry3d extrinsic() {
  // A roof-mounted sensor: 1.2 m forward, 0.5 m left, 1.9 m up, yawed 90 degrees.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.2, 0.5, 1.9);
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

TEST(CloudMergerAssembly, TransformMovesPointsAndDropsNonFinite) {
  CloudData out;
  EXPECT_EQ(transformCloud(threePoints(), extrinsic(), out), 1u);
  ASSERT_EQ(out.points.size(), 2u);
  // (1, 0, 0) rotated by 90 degrees is (0, 1, 0), then translated.
  EXPECT_NEAR(out.points[0].x(), 1.2f, 1e-6f);
  EXPECT_NEAR(out.points[0].y(), 1.5f, 1e-6f);
  EXPECT_NEAR(out.points[0].z(), 1.9f, 1e-6f);
  // (0, 2, -1) -> (-2, 0, -1) + t.
  EXPECT_NEAR(out.points[1].x(), -0.8f, 1e-6f);
  EXPECT_NEAR(out.points[1].y(), 0.5f, 1e-6f);
  EXPECT_NEAR(out.points[1].z(), 0.9f, 1e-6f);
  // The fields of the dropped point went with it.
  EXPECT_EQ(out.time_s, std::vector<float>({0.01f, 0.03f}));
  EXPECT_EQ(out.intensity, std::vector<float>({10.f, 30.f}));
  EXPECT_EQ(out.ring, std::vector<uint16_t>({1, 3}));
  EXPECT_EQ(out.label, std::vector<uint8_t>({0, 2}));
}

TEST(CloudMergerAssembly, FieldOfTheWrongSizeIsLeftOut) {
  CloudData in = threePoints();
  in.ring.pop_back();
  CloudData out;
  transformCloud(in, Eigen::Isometry3d::Identity(), out);
  EXPECT_TRUE(out.ring.empty());
  EXPECT_EQ(out.intensity.size(), 2u);
}

MergeInput input(size_t sensor, int64_t stamp_ns, CloudData cloud) {
  MergeInput in;
  in.sensor = sensor;
  in.stamp_ns = stamp_ns;
  in.cloud = std::make_shared<CloudData>(std::move(cloud));
  return in;
}

TEST(CloudMergerAssembly, MergeRebasesTimesToTheEarliestStamp) {
  CloudData a, b;
  transformCloud(threePoints(), Eigen::Isometry3d::Identity(), a);
  b = a;
  MergeCycle cycle;
  cycle.stamp_ns = 1'000'000'000;
  cycle.inputs = {input(0, 1'000'000'000, a), input(2, 1'051'000'000, b)};
  const CloudData m = mergeCycle(cycle);
  ASSERT_EQ(m.points.size(), 4u);
  ASSERT_EQ(m.time_s.size(), 4u);
  EXPECT_FLOAT_EQ(m.time_s[0], 0.01f);
  EXPECT_FLOAT_EQ(m.time_s[1], 0.03f);
  EXPECT_NEAR(m.time_s[2], 0.061f, 1e-6f);
  EXPECT_NEAR(m.time_s[3], 0.081f, 1e-6f);
  EXPECT_EQ(m.ring, std::vector<uint16_t>({1, 3, 1, 3}));
  EXPECT_EQ(m.label.size(), 4u);
  EXPECT_EQ(m.points[2], a.points[0]);
}

TEST(CloudMergerAssembly, FieldsMissingInOneInput) {
  CloudData a, b;
  transformCloud(threePoints(), Eigen::Isometry3d::Identity(), a);
  b = a;
  b.time_s.clear();     // a sensor without per-point time: its points get the cloud's offset
  b.intensity.clear();  // no intensity anywhere rather than invented values
  MergeCycle cycle;
  cycle.stamp_ns = 5'000'000'000;
  cycle.inputs = {input(0, 5'000'000'000, a), input(1, 5'020'000'000, b)};
  const CloudData m = mergeCycle(cycle);
  ASSERT_EQ(m.time_s.size(), 4u);
  EXPECT_NEAR(m.time_s[2], 0.02f, 1e-6f);
  EXPECT_NEAR(m.time_s[3], 0.02f, 1e-6f);
  EXPECT_TRUE(m.intensity.empty());
  EXPECT_EQ(m.ring.size(), 4u);
}

TEST(CloudMergerAssembly, EmptyCycle) {
  MergeCycle cycle;
  cycle.inputs = {input(0, 0, CloudData())};
  const CloudData m = mergeCycle(cycle);
  EXPECT_TRUE(m.points.empty());
  EXPECT_TRUE(m.time_s.empty());
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
