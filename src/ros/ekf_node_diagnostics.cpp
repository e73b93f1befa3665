// EkfNode health on /diagnostics (ekf_node.h): input rates and dropouts, fused / rejected counts
// per source, position and yaw sigma, time since the last fused match, resets and lockouts; the
// IMU and INS topics' rate and stamp checks, and the console lines of a silent input.
#include <cmath>
#include <cstdio>

#include "gmm_localization/ros/ekf_node.h"

namespace gmm_localization {
namespace node {
namespace {

/// Seconds since a wall time, or -1 when never.
double since(const ros::WallTime& t) {
  return t.isZero() ? -1.0 : (ros::WallTime::now() - t).toSec();
}

}  // namespace

void EkfNode::setupDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  diagnostics_->add("filter", [this](StatusBuilder& s) {
    std::lock_guard<std::mutex> lock(mutex_);
    const EkfDiagnostics d = filter_->ekf().diagnostics();
    s.add("running", filter_->active());
    s.add("horizontal sigma (max) [m]", fixed(d.max_horizontal_sigma_m, 3));
    s.add("yaw sigma [deg]", fixed(d.yaw_sigma_rad * 180.0 / M_PI, 2));
    if (std::isfinite(d.gyro_bias_sigma_radps)) {
      s.add("IMU gyro bias x, y, z [mrad/s] (sigma)",
            fixed(1e3 * d.gyro_bias_radps.x(), 3) + ", " + fixed(1e3 * d.gyro_bias_radps.y(), 3) +
                ", " + fixed(1e3 * d.gyro_bias_radps.z(), 3) + " (" +
                fixed(1e3 * d.gyro_bias_sigma_radps, 3) + ")");
    }
    s.add("INS twist scale error [%] (sigma)",
          fixed(100.0 * d.twist_scale, 3) + " (" + fixed(100.0 * d.twist_scale_sigma, 3) + ")");
    for (int i = 0; i < kMeasurementSourceCount; ++i) {
      const bool gnss = i == static_cast<int>(MeasurementSource::kGnssPosition);
      if (gnss && !options_.filter.gnss_enabled) continue;  // the optional input, off
      const SourceCounters& c = d.sources[i];
      s.add(std::string(sourceName(static_cast<MeasurementSource>(i))) +
                " fused / gated / invalid / too old / stale / other",
            std::to_string(c.fused) + " / " + std::to_string(c.rejected_gate) + " / " +
                std::to_string(c.rejected_invalid) + " / " + std::to_string(c.rejected_too_old) +
                " / " + std::to_string(c.rejected_stale) + " / " +
                std::to_string(c.rejected_other));
    }
    if (options_.filter.gnss_enabled) {
      s.add("gnss fixes received / refused",
            std::to_string(gnss_fixes_) + " / " + std::to_string(filter_->gnssRefused()));
      s.add("gnss map georeference", georeference_text_);
      if (std::isfinite(d.gnss_bias_sigma_m)) {
        s.add("gnss receiver bias x, y [m] (sigma)", fixed(d.gnss_bias_m.x(), 2) + ", " +
                                                         fixed(d.gnss_bias_m.y(), 2) + " (" +
                                                         fixed(d.gnss_bias_sigma_m, 2) + ")");
      }
      if (!gnss_last_problem_.empty()) s.add("gnss last problem", gnss_last_problem_);
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
    const double now_s = ros::WallTime::now().toSec();
    // Seconds since the input's last message, -1 when never.
    auto age = [&](size_t input) {
      return inputs_.everHeard(input) ? inputs_.silentFor(input, now_s) : -1.0;
    };
    s.add("imu rate [Hz]", fixed(inputs_.rateHz(imu_input_, now_s), 1));
    s.add("odom rate [Hz]", fixed(inputs_.rateHz(odom_input_, now_s), 1));
    s.add("scan match rate [Hz]", fixed(inputs_.rateHz(match_input_, now_s), 2));
    const double imu_age = age(imu_input_), odom_age = age(odom_input_),
                 match_age = age(match_input_);
    s.add("time since imu [s]", fixed(imu_age, 2));
    s.add("time since odom [s]", fixed(odom_age, 2));
    s.add("time since scan match [s]", fixed(match_age, 2));
    // A source that has spoken and went silent briefly gets a dropout line; one silent for
    // the watchdog's 5 s gets the line that names the fix (warnSilentInputs).
    if (options_.use_imu && (imu_age < 0.0 || imu_age > options_.imu_timeout_s)) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "IMU dropout");
      if (imu_age > 0.0 && !inputs_.silent(imu_input_, now_s)) {
        ROS_WARN_THROTTLE(5.0,
                          "%s: IMU dropout: no sample for %.1f s (imu_timeout_s %.1f); the "
                          "filter predicts without it",
                          name_.c_str(), imu_age, options_.imu_timeout_s);
      }
    }
    if (odom_age < 0.0 || odom_age > options_.odom_timeout_s) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "INS odometry dropout");
      if (odom_age > 0.0 && !inputs_.silent(odom_input_, now_s)) {
        ROS_WARN_THROTTLE(5.0,
                          "%s: INS odometry dropout: no message for %.1f s (odom_timeout_s "
                          "%.1f); the filter predicts without its twist",
                          name_.c_str(), odom_age, options_.odom_timeout_s);
      }
    }
    if (match_age < 0.0 || match_age > options_.match_timeout_s) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no scan matches");
    }
    warnSilentInputs(now_s);
  });
  auto topic_status = [this](FrequencyMonitor& rate, size_t input, const std::string& topic,
                             const char* fix) {
    return [this, &rate, input, topic, fix](StatusBuilder& s) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const double now_s = ros::WallTime::now().toSec();
        s.add("topic", topic);
        s.add("messages received", inputs_.count(input));
        s.add("time since last message [s]", fixed(inputs_.silentFor(input, now_s), 2));
        if (inputs_.silent(input, now_s)) {
          s.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                    "no messages on " + topic + " " +
                        silenceText(inputs_.everHeard(input), inputs_.silentFor(input, now_s)) +
                        " (" + fix + ")");
        }
      }
      rate.fill(s);
    };
  };
  if (options_.use_imu) {
    diagnostics_->add(imu_topic_ + " topic status",
                      topic_status(imu_rate_, imu_input_, imu_topic_,
                                   "launch argument imu_topic, or use_imu false"));
  }
  diagnostics_->add(
      odom_topic_ + " topic status",
      topic_status(odom_rate_, odom_input_, odom_topic_, "launch argument odom_topic"));
}

void EkfNode::warnSilentInputs(double now_s) {
  for (const InputSilence& silence : inputs_.due(now_s)) {
    const std::string when = silenceText(silence.ever_heard, silence.silent_for_s);
    if (silence.input == imu_input_) {
      ROS_WARN(
          "%s: IMU dropout: no messages on %s %s: is the IMU driver or the bag running? "
          "The EKF reads `imu`, remapped to the launch argument imu_topic; to run without an "
          "IMU set use_imu: false in its parameters (config/ekf.yaml). Meanwhile the filter "
          "predicts without it",
          name_.c_str(), silence.name.c_str(), when.c_str());
    } else {
      ROS_WARN(
          "%s: INS odometry dropout: no messages on %s %s: is the INS driver or the bag "
          "running? The EKF and the matcher read `odom`, remapped to the launch argument "
          "odom_topic (nav_msgs/Odometry, odom -> base_link). Meanwhile the filter predicts "
          "without its twist and the matcher does not deskew",
          name_.c_str(), silence.name.c_str(), when.c_str());
    }
  }
}

}  // namespace node
}  // namespace gmm_localization
