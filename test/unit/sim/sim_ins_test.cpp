// The INS model against its configuration: deterministic drift from scale and heading errors,
// heading random-walk growth and IMU biases, measured over seeded runs.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/sim/ins_model.h"
#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

class InsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto t = Town::generate(testing::smallTown());
    ASSERT_TRUE(t);
    town_ = std::make_unique<Town>(std::move(*t));
    RouteConfig rc;
    rc.nodes = {{0, 1}, {1, 1}, {2, 1}, {3, 1}, {4, 1}};  // straight east
    auto r = Route::plan(*town_, rc);
    ASSERT_TRUE(r) << r.error();
    route_ = std::make_unique<Route>(std::move(*r));
    KinematicsConfig kc;
    kc.stop_probability = 0.0;
    kc.lane_wander_m = 0.0;
    auto tr = Trajectory::create(*town_, *route_, kc);
    ASSERT_TRUE(tr);
    traj_ = std::make_unique<Trajectory>(std::move(*tr));
  }
  static InsConfig noiseless() {
    InsConfig c;
    c.scale_error = c.heading_bias_rad = c.heading_random_walk_rad_sqrt_s = 0.0;
    c.position_random_walk_m_sqrt_s = c.position_noise_m = c.attitude_noise_rad =
        c.velocity_noise_mps = 0.0;
    c.gyro_noise_rad_s = c.gyro_bias_rad_s = c.accel_noise_mps2 = c.accel_bias_mps2 = 0.0;
    return c;
  }
  std::unique_ptr<Town> town_;
  std::unique_ptr<Route> route_;
  std::unique_ptr<Trajectory> traj_;
};

TEST_F(InsTest, ScaleAndHeadingErrorsDriftAlongAndAcrossTrack) {
  InsConfig c = noiseless();
  c.scale_error = 0.01;
  c.heading_bias_rad = 0.01;
  InsModel ins(*traj_, c, 0.0);
  std::vector<OdomSample> odom;
  ins.advanceTo(traj_->duration(), &odom, nullptr);
  ASSERT_GT(odom.size(), 1000u);
  const Eigen::Vector3d p0 = traj_->pose(0.0).translation();
  const OdomSample& last = odom.back();
  const Eigen::Vector3d gt = traj_->pose(last.t).translation() - p0;
  const Eigen::Vector3d od = last.pose.translation() - p0;
  const Eigen::Vector2d along = gt.head<2>().normalized(), across(-along.y(), along.x());
  const double L = gt.head<2>().norm();
  ASSERT_GT(L, 250.0);
  // Along track: (1 + s) cos(b) L - L ~ s L; across: (1 + s) sin(b) L ~ b L (to the left).
  EXPECT_NEAR((od.head<2>() - gt.head<2>()).dot(along), ((1.01 * std::cos(0.01)) - 1.0) * L,
              1e-3 * L);
  EXPECT_NEAR((od.head<2>() - gt.head<2>()).dot(across), 1.01 * std::sin(0.01) * L, 1e-3 * L);
  // Orientation: heading offset by the bias.
  const double yaw_gt =
      std::atan2(traj_->pose(last.t).linear()(1, 0), traj_->pose(last.t).linear()(0, 0));
  const double yaw_od = std::atan2(last.pose.linear()(1, 0), last.pose.linear()(0, 0));
  EXPECT_NEAR(yaw_od - yaw_gt, 0.01, 1e-6);
}

TEST_F(InsTest, HeadingRandomWalkGrowsWithSquareRootOfTime) {
  const double sigma = 0.002, horizon = 16.0;
  std::vector<double> drift;
  for (int seed = 0; seed < 120; ++seed) {
    InsConfig c = noiseless();
    c.seed = 1000 + seed;
    c.heading_random_walk_rad_sqrt_s = sigma;
    c.imu_rate_hz = 10.0;
    InsModel ins(*traj_, c, 2.0);
    std::vector<OdomSample> odom;
    ins.advanceTo(2.0 + horizon + 1e-9, &odom, nullptr);
    drift.push_back(odom.back().heading_error_rad);
  }
  double mean = 0, var = 0;
  for (double d : drift) mean += d / drift.size();
  for (double d : drift) var += (d - mean) * (d - mean) / (drift.size() - 1);
  const double expected = sigma * std::sqrt(horizon);
  EXPECT_NEAR(mean, 0.0, 3.0 * expected / std::sqrt(drift.size()));
  EXPECT_NEAR(std::sqrt(var), expected, 0.2 * expected);  // ~3 standard errors with 120 runs
}

TEST_F(InsTest, ImuBiasesAndGravityMatchTheConfiguration) {
  const double gyro_bias = 0.01, accel_bias = 0.05;
  std::vector<double> bx, az;
  for (int seed = 0; seed < 100; ++seed) {
    InsConfig c = noiseless();
    c.seed = 77 + seed;
    c.gyro_bias_rad_s = gyro_bias;
    c.accel_bias_mps2 = accel_bias;
    c.gyro_noise_rad_s = 0.002;
    c.accel_noise_mps2 = 0.03;
    InsModel ins(*traj_, c, 0.0);
    std::vector<ImuSample> imu;
    ins.advanceTo(1.0, nullptr, &imu);  // at the start the vehicle pulls away slowly
    double gx = 0.0, sz = 0.0;
    for (const ImuSample& m : imu) {
      const VehicleState s = traj_->state(m.t);
      gx += (m.angular_velocity - s.angular_velocity_body).x() / imu.size();
      const Eigen::Vector3d f = s.pose.linear().transpose() *
                                (s.acceleration_world + Eigen::Vector3d(0, 0, InsModel::kGravity));
      sz += (m.linear_acceleration - f).z() / imu.size();
    }
    bx.push_back(gx);
    az.push_back(sz);
  }
  auto stddev = [](const std::vector<double>& v) {
    double m = 0, s = 0;
    for (double x : v) m += x / v.size();
    for (double x : v) s += (x - m) * (x - m) / (v.size() - 1);
    return std::sqrt(s);
  };
  EXPECT_NEAR(stddev(bx), gyro_bias, 0.2 * gyro_bias);
  EXPECT_NEAR(stddev(az), accel_bias, 0.2 * accel_bias);
  // Gravity: at rest the specific force is ~ +9.81 up.
  InsModel ins(*traj_, noiseless(), 0.0);
  std::vector<ImuSample> imu;
  ins.advanceTo(0.01, nullptr, &imu);
  ASSERT_FALSE(imu.empty());
  EXPECT_NEAR(imu.front().linear_acceleration.norm(), InsModel::kGravity, 0.2);
  EXPECT_GT(imu.front().linear_acceleration.z(), 9.7);
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
