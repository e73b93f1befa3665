// The LocalizerPipeline options built from the nodelets' options carry every shared setting,
// so `evaluate` reproduces the nodelets from the same YAML files.
#include "gmm_localization/ros/matcher_options.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

TEST(MatcherOptions, PipelineOptionsMirrorTheNodeletOptions) {
  MatcherOptions m;
  m.registration.heading_step_rad = 0.004;
  m.policy.window.max_half_xy_m = 7.0;
  m.policy.acceptance.min_map_coverage = 0.55;
  m.session.deskew = false;
  m.session.deskew_twist_max_gap_s = 0.33;
  m.session.odometry_buffer_s = 4.0;
  m.session.odometry_max_extrapolation_s = 0.12;
  m.session.time_backwards_tolerance_s = 2.5;
  m.session.configured_pose_on_reset = false;
  m.session.scan_queue_size = 5;
  m.initial_pose_half_xy_m = 4.0;
  m.initial_pose_half_heading_rad = 0.2;
  m.method.method = MatchMethod::kFused;
  EkfNodeOptions e;
  e.ekf.history_length_s = 3.0;
  e.filter.gate_lockout_count = 9;
  e.filter.defaults.twist_linear_sigma_mps = 0.3;

  const LocalizerPipelineOptions o = pipelineOptions(m, e);
  EXPECT_EQ(o.registration.heading_step_rad, 0.004);
  EXPECT_EQ(o.policy.window.max_half_xy_m, 7.0);
  EXPECT_EQ(o.policy.acceptance.min_map_coverage, 0.55);
  EXPECT_FALSE(o.session.deskew);
  EXPECT_EQ(o.session.deskew_twist_max_gap_s, 0.33);
  EXPECT_EQ(o.session.odometry_buffer_s, 4.0);
  EXPECT_EQ(o.session.odometry_max_extrapolation_s, 0.12);
  EXPECT_EQ(o.session.time_backwards_tolerance_s, 2.5);
  EXPECT_FALSE(o.session.configured_pose_on_reset);
  // The scan queue too: the pipeline models the nodelet's queue, not a single slot.
  EXPECT_EQ(o.session.scan_queue_size, 5);
  // The method: `evaluate --method fused` runs the nodelets' options with method: fused.
  EXPECT_EQ(o.method.method, MatchMethod::kFused);
  EXPECT_EQ(o.ekf.history_length_s, 3.0);
  EXPECT_EQ(o.filter.gate_lockout_count, 9);
  EXPECT_EQ(o.filter.defaults.twist_linear_sigma_mps, 0.3);
  EXPECT_EQ(o.validate(), "");
  const WindowExtent w = configuredPoseWindow(m);
  EXPECT_EQ(w.half_x_m, 4.0);
  EXPECT_EQ(w.half_y_m, 4.0);
  EXPECT_EQ(w.half_heading_rad, 0.2);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
