// EkfNode health on /diagnostics (ekf_node.h): input rates and dropouts, fused / rejected counts
// per source, position and yaw sigma, time since the last fused match, resets and lockouts.
#include <cmath>
#include <cstdio>

#include "gmm_localization/ros/ekf_node.h"

namespace gmm_localization {
namespace node {
namespace {

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

/// Seconds since a wall time, or -1 when never.
double since(const ros::WallTime& t) {
  return t.isZero() ? -1.0 : (ros::WallTime::now() - t).toSec();
}

}  // namespace

void EkfNode::setupDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, name_);
  diagnostics_->add("filter", [this](StatusBuilder& s) {
    std::lock_guard<std::mutex> lock(mutex_);
    const EkfDiagnostics d = filter_->ekf().diagnostics();
    s.add("running", filter_->active());
    s.add("horizontal sigma (max) [m]", fixed(d.max_horizontal_sigma_m, 3));
    s.add("yaw sigma [deg]", fixed(d.yaw_sigma_rad * 180.0 / M_PI, 2));
    for (int i = 0; i < kMeasurementSourceCount; ++i) {
      const SourceCounters& c = d.sources[i];
      s.add(std::string(sourceName(static_cast<MeasurementSource>(i))) +
                " fused / gated / invalid / too old / stale / other",
            std::to_string(c.fused) + " / " + std::to_string(c.rejected_gate) + " / " +
                std::to_string(c.rejected_invalid) + " / " + std::to_string(c.rejected_too_old) +
                " / " + std::to_string(c.rejected_stale) + " / " +
                std::to_string(c.rejected_other));
    }
    s.add("delayed measurements", d.delayed_measurements);
    // Messages dropped for their stamp (an IMU message counts once, whatever its parts).
    s.add("far-future messages (time jumps)", d.time_forward_jump_events);
    s.add("stale messages in a row", d.consecutive_stale);
    s.add("time went backwards (reports)", d.time_backwards_events);
    s.add("stops (time went backwards or jumped)", filter_->stops());
    s.add("gate lockouts", filter_->lockouts());
    s.add("consecutive gated matches", filter_->consecutiveGateRejections());
    s.add("published estimates", published_);
    s.add("publish failures", publish_failures_);
    s.add("invalid inputs", bad_inputs_);
    s.add("last event", last_event_);
    const double match_age = since(last_fused_match_wall_);
    s.add("time since last fused match [s]", fixed(match_age, 2));
    if (!filter_->active()) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                "not running: waiting for an initial pose or a scan match");
    } else if (match_age < 0.0 || match_age > options_.match_timeout_s) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no scan match fused recently");
    }
    if (!last_publish_problem_.empty() && publish_failures_ > 0)
      s.add("last publish problem", last_publish_problem_);
  });
  diagnostics_->add("inputs", [this](StatusBuilder& s) {
    std::lock_guard<std::mutex> lock(mutex_);
    s.add("imu rate [Hz]", fixed(imu_rate_.rateHz(), 1));
    s.add("odom rate [Hz]", fixed(odom_rate_.rateHz(), 1));
    s.add("scan match rate [Hz]", fixed(match_rate_.rateHz(), 2));
    const double imu_age = since(last_imu_wall_), odom_age = since(last_odom_wall_),
                 match_age = since(last_match_wall_);
    s.add("time since imu [s]", fixed(imu_age, 2));
    s.add("time since odom [s]", fixed(odom_age, 2));
    s.add("time since scan match [s]", fixed(match_age, 2));
    if (options_.use_imu && (imu_age < 0.0 || imu_age > options_.imu_timeout_s)) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "IMU dropout");
      // A source that has spoken and went silent (not one that never started) is worth a line.
      if (imu_age > 0.0) {
        ROS_WARN_THROTTLE(5.0,
                          "%s: IMU dropout: no sample for %.1f s (imu_timeout_s %.1f); the "
                          "filter predicts without it",
                          name_.c_str(), imu_age, options_.imu_timeout_s);
      }
    }
    if (odom_age < 0.0 || odom_age > options_.odom_timeout_s) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "INS odometry dropout");
      if (odom_age > 0.0) {
        ROS_WARN_THROTTLE(5.0,
                          "%s: INS odometry dropout: no message for %.1f s (odom_timeout_s "
                          "%.1f); the filter predicts without its twist",
                          name_.c_str(), odom_age, options_.odom_timeout_s);
      }
    }
    if (match_age < 0.0 || match_age > options_.match_timeout_s) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no scan matches");
    }
  });
}

}  // namespace node
}  // namespace gmm_localization
