#pragma once
// Configuration of the EKF core (one typed struct, validated once; DESIGN.md 3). The member
// names are the parameter keys the ekf nodelet loads.

#include <array>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

/// How the IMU's specific force is turned into the body acceleration state (gravity removed).
enum class GravityRemoval {
  /// The measurement model is the specific force itself, h(x) = a + R(roll, pitch)^T g_up,
  /// evaluated with the filter's roll/pitch at the time of fusion (and again at every replay),
  /// with its full Jacobian: the accelerometer then also observes tilt, as it physically does.
  /// This is the consistent EKF choice (ignoring the tilt terms made the velocity estimate
  /// overconfident by an order of magnitude in ekf_simulation_test).
  kStateEstimate,
  /// a = f - R_imu^T g_up with the orientation reported in the same IMU message (as
  /// robot_localization does), fused as a direct measurement of a: the accelerometer does not
  /// touch roll/pitch. Use it when the IMU orientation was computed from this same
  /// accelerometer and should not be counted twice. The orientation's roll/pitch covariance is
  /// propagated into the acceleration covariance. An IMU message without orientation (or with
  /// an invalid roll/pitch covariance) gets its acceleration rejected.
  kMeasuredOrientation,
};

struct EkfOptions {
  /// How far back measurements can be inserted [s], range (0, 60]. A measurement older than
  /// the newest fused one by more than this is rejected as too old. Scan matches arrive
  /// 50-150 ms after their stamp; 2 s leaves room for a slow match.
  double history_length_s = 2.0;
  /// Upper bound on the number of stored history entries, range [10, 1000000]. Bounds memory
  /// (about 2 kB per entry) when sensors run faster than expected; the oldest go first.
  int max_history_entries = 10000;
  /// A stamp older than the newest filter time by more than this is stale [s]; range
  /// [history_length_s, 1e6]. A stale message is dropped (kRejectedStale, with the reason) and
  /// counted; time going backwards (a looping rosbag: the caller should reset) is reported only
  /// for a sustained run of them (stale_reset_count) or for one far older
  /// (time_backwards_reset_s). One glitched IMU or odometry stamp thus never resets the filter.
  double time_backwards_tolerance_s = 5.0;
  /// Consecutive stale messages (each message counted once, whatever its parts) after which
  /// time is reported to have gone backwards; range [1, 1e6]. A message within the tolerance
  /// ends the run. At 100 Hz IMU and 50 Hz odometry, 10 messages are about 70 ms of a loop.
  int stale_reset_count = 10;
  /// A stamp older than the filter time by more than this is time going backwards at once [s],
  /// range [time_backwards_tolerance_s, 1e6]: no late or glitched sensor message is that old,
  /// a rosbag that looped is.
  double time_backwards_reset_s = 10.0;
  /// Largest prediction interval accepted [s], range (0, 3600]. A measurement (or stateAt
  /// query) further ahead of the filter time is refused as a forward time jump: the caller
  /// should reset. Also bounds the work of one prediction.
  double max_prediction_gap_s = 5.0;
  /// Predictions are integrated in sub-steps no longer than this [s], range [1e-4, 1].
  double max_prediction_step_s = 0.02;
  /// Magnitude of gravity [m/s^2], range [9.7, 9.9].
  double gravity_mps2 = 9.80665;
  /// Diagonal floor applied to every measurement covariance [unit^2], range [0, 1]. Keeps an
  /// over-confident (zero) covariance from making the update singular.
  double min_measurement_variance = 1e-9;

  /// Process noise spectral density per state from x to the twist scale (the GNSS and gyro
  /// biases have their own models, gnss_bias_* and gyro_bias_* below), in state order
  /// [unit^2 / s], each finite and
  /// >= 0: a prediction over dt adds Q = diag(q) * dt. Position and orientation integrate the
  /// velocities exactly, so theirs only absorb model error; velocities, rates and
  /// accelerations are random walks whose density sets how fast the filter follows changes.
  /// The defaults are tuned on ekf_simulation_test's car (changing speed and yaw rate, rolling
  /// ground): they keep it slightly conservative (NEES below its dimension), not overconfident.
  /// The twist scale's density sets how fast a change of the INS scale is followed: 1e-9/s
  /// lets it wander by 0.1 % in 1000 s.
  std::array<double, kTunedStateCount> process_noise_density = {
      1e-4, 1e-4, 1e-4,  // x, y, z            [m^2/s]
      1e-6, 1e-6, 1e-6,  // roll, pitch, yaw   [rad^2/s]
      1e-3, 1e-3, 1e-3,  // vx, vy, vz         [(m/s)^2/s]
      1e-2, 1e-2, 1e-2,  // wx, wy, wz         [(rad/s)^2/s]
      1.0,  1.0,  1.0,   // ax, ay, az         [(m/s^2)^2/s]
      1e-9};             // twist scale        [1/s]

  /// Initial variance per state after reset() for the states the caller does not give (the
  /// pose block comes with reset(), so only entries 6..15 are used), each finite and > 0
  /// [unit^2]. Wide on purpose: reset() sets velocity, rates and acceleration to zero, and a
  /// vehicle already moving at 20 m/s must not have its first twist gated out.
  /// The twist scale starts at 0 with this variance (1e-4: a 1 % scale error is one sigma).
  std::array<double, kTunedStateCount> initial_variance = {1.0,   1.0,   1.0,    // x, y, z
                                                           0.01,  0.01,  0.1,    // roll, pitch, yaw
                                                           400.0, 400.0, 400.0,  // vx, vy, vz
                                                           1.0,   1.0,   1.0,    // wx, wy, wz
                                                           25.0,  25.0,  25.0,   // ax, ay, az
                                                           1e-4};                // twist scale

  /// Mahalanobis gates, as the probability mass of the chi-square distribution (with the
  /// measurement's dimension as degrees of freedom) that is accepted, range (0, 1]; 1 disables
  /// the gate. 0.9999 rejects about one consistent measurement in 10^4.
  double pose_gate_probability = 0.9999;
  double twist_gate_probability = 0.999999;
  double imu_gate_probability = 0.999999;
  /// For GNSS positions (processPosition): a fix whose innovation falls outside is dropped
  /// (multipath, a jump); its covariance is the receiver's, so the gate is wide for it.
  double gnss_gate_probability = 0.9999;

  /// Which parts of an IMU message are fused (its yaw is never fused: it is not absolute).
  bool imu_use_orientation = true;          ///< roll and pitch
  bool imu_use_angular_velocity = true;     ///< wx, wy, wz
  bool imu_use_linear_acceleration = true;  ///< ax, ay, az after gravity removal
  GravityRemoval imu_gravity_removal = GravityRemoval::kStateEstimate;

  /// Which parts of an odometry twist are fused.
  bool twist_use_linear = true;   ///< vx, vy, vz
  bool twist_use_angular = true;  ///< wx, wy, wz
  /// Estimate the scale error s of the INS linear twist (the twist model is then
  /// z = (1 + s) v, ekf_state.h). false: z = v, s stays 0 and is never coupled to the rest.
  bool estimate_twist_scale = true;
  /// Estimate the GNSS receiver's slow bias b (ekf_state.h): a fix then reads position + b, and
  /// b is a first-order Gauss-Markov process, b' = -b / tau + white noise, of stationary sigma
  /// gnss_bias_sigma_m per horizontal axis and correlation time gnss_bias_tau_s; it starts at 0
  /// with variance sigma^2. false: fixes read the position, b stays 0 and uncoupled (each fix
  /// is then independent, and a few hundred of them make the filter sure of their mean).
  /// The defaults: a single-frequency receiver in a town (1 m, a minute).
  bool estimate_gnss_bias = true;
  double gnss_bias_sigma_m = 1.0;
  double gnss_bias_tau_s = 60.0;
  /// Estimate the IMU gyro's bias g (ekf_state.h): the IMU's rates then read w + g, the INS
  /// twist's rates w. g starts at 0 with sigma gyro_bias_sigma_radps per axis and is a random
  /// walk of density gyro_bias_random_walk [(rad/s)^2/s]. false: the IMU's rates read w (an
  /// IMU whose output its INS compensates). Defaults: a tactical MEMS gyro (0.5 mrad/s, a bias
  /// that wanders by 0.03 mrad/s in an hour).
  bool estimate_gyro_bias = true;
  double gyro_bias_sigma_radps = 0.002;
  double gyro_bias_random_walk = 1e-12;

  /// Success, or a reason naming the first offending key, its value and the allowed range.
  Status validate() const;
};

/// Key name of a GravityRemoval value ("state_estimate", "measured_orientation").
const char* gravityRemovalName(GravityRemoval mode);

}  // namespace gmm_localization
