#include "gmm_localization/core/filter/ekf_options.h"

#include <cmath>
#include <sstream>
#include <string>

namespace gmm_localization {
namespace {

// Checks lo <= value <= hi (or lo < value when lo_open), naming the key on failure.
bool inRange(const char* key, double value, double lo, double hi, bool lo_open, std::string* why) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  if (!ok) {
    std::ostringstream s;
    s << "ekf option " << key << " = " << value << " is outside the allowed range "
      << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
    *why = s.str();
  }
  return ok;
}

bool perStateValid(const char* key, const std::array<double, kTunedStateCount>& values,
                   bool positive, std::string* why) {
  for (int i = 0; i < kTunedStateCount; ++i) {
    const double v = values[i];
    if (std::isfinite(v) && (positive ? v > 0.0 : v >= 0.0)) continue;
    std::ostringstream s;
    s << "ekf option " << key << "[" << i << "] (" << stateName(i) << ") = " << v
      << " must be finite and " << (positive ? "> 0" : ">= 0");
    *why = s.str();
    return false;
  }
  return true;
}

}  // namespace

Status EkfOptions::validate() const {
  std::string why;
  const bool ok =
      inRange("history_length_s", history_length_s, 0.0, 60.0, true, &why) &&
      inRange("max_history_entries", max_history_entries, 10, 1e6, false, &why) &&
      inRange("time_backwards_tolerance_s", time_backwards_tolerance_s, history_length_s, 1e6,
              false, &why) &&
      inRange("stale_reset_count", stale_reset_count, 1, 1e6, false, &why) &&
      inRange("time_backwards_reset_s", time_backwards_reset_s, time_backwards_tolerance_s, 1e6,
              false, &why) &&
      inRange("max_prediction_gap_s", max_prediction_gap_s, 0.0, 3600.0, true, &why) &&
      inRange("max_prediction_step_s", max_prediction_step_s, 1e-4, 1.0, false, &why) &&
      inRange("gravity_mps2", gravity_mps2, 9.7, 9.9, false, &why) &&
      inRange("min_measurement_variance", min_measurement_variance, 0.0, 1.0, false, &why) &&
      perStateValid("process_noise_density", process_noise_density, false, &why) &&
      perStateValid("initial_variance", initial_variance, true, &why) &&
      inRange("pose_gate_probability", pose_gate_probability, 0.0, 1.0, true, &why) &&
      inRange("twist_gate_probability", twist_gate_probability, 0.0, 1.0, true, &why) &&
      inRange("imu_gate_probability", imu_gate_probability, 0.0, 1.0, true, &why) &&
      inRange("gnss_gate_probability", gnss_gate_probability, 0.0, 1.0, true, &why) &&
      inRange("gnss_bias_sigma_m", gnss_bias_sigma_m, 0.0, 100.0, true, &why) &&
      inRange("gnss_bias_tau_s", gnss_bias_tau_s, 0.0, 1e6, true, &why) &&
      inRange("gyro_bias_sigma_radps", gyro_bias_sigma_radps, 0.0, 1.0, true, &why) &&
      inRange("gyro_bias_random_walk", gyro_bias_random_walk, 0.0, 1.0, false, &why);
  if (!ok) return Status::failure(why);
  if (imu_gravity_removal != GravityRemoval::kStateEstimate &&
      imu_gravity_removal != GravityRemoval::kMeasuredOrientation) {
    return Status::failure(
        "ekf option imu_gravity_removal must be state_estimate or measured_orientation");
  }
  return Status::success();
}

const char* gravityRemovalName(GravityRemoval mode) {
  switch (mode) {
    case GravityRemoval::kStateEstimate:
      return "state_estimate";
    case GravityRemoval::kMeasuredOrientation:
      return "measured_orientation";
  }
  return "unknown";
}

}  // namespace gmm_localization
