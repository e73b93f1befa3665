#pragma once
// Kinematic prediction of the EKF: constant body velocity, rate and acceleration in 3D.
//
// Continuous model (state layout in ekf_state.h; R = map_R_base(roll, pitch, yaw)):
//   d p / dt     = R v                 position integrates the body velocity in the map frame
//   d rpy / dt   = E(roll, pitch) w    Euler-angle rates from body rates
//   d v / dt     = a - w x v           body velocity in a rotating frame (a car on a curve at
//                                      constant speed has a = w x v, the centripetal term, and
//                                      constant v; robot_localization omits the w x v term)
//   d w / dt = 0,  d a / dt = 0        plus white noise: random walks
// One discrete step of length dt: p += R (v dt + a dt^2 / 2), rpy += E w dt,
// v += (a - w x v) dt; angles are wrapped afterwards. Process noise Q = diag(q) dt with q the
// per-state spectral densities (EkfOptions::process_noise_density).
// The GNSS bias b (ekf_state.h) is a first-order Gauss-Markov process, discretised exactly:
// b <- e b and its variance gains (1 - e^2) sigma^2, e = exp(-dt / tau), so that sigma^2 is
// its stationary variance; tau = 0 holds b (and its variance) constant. The gyro bias is a
// random walk: its variance gains its density times dt.

#include <array>

#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

/// One discrete step f(x, dt) of the model above. If jacobian is not null it receives
/// F = df/dx at x. dt_s >= 0 [s]; dt_s = 0 returns x unchanged (angles wrapped) and F = I.
StateVector predictStep(const StateVector& x, double dt_s, StateCovariance* jacobian);

/// The calibration states' processes (EkfOptions::gnss_bias_*, gyro_bias_random_walk): the
/// GNSS bias's Gauss-Markov process (tau_s = 0: held constant) and the gyro bias's random walk.
struct CalibrationProcess {
  double gnss_bias_sigma_m = 0.0;
  double gnss_bias_tau_s = 0.0;
  double gyro_bias_density = 0.0;  ///< [(rad/s)^2/s]
};

/// Advances state (mean, covariance and time_s) to time_s, integrating in sub-steps of at most
/// max_step_s: x <- f(x, dt), P <- F P F^T + Q dt, then P is symmetrised. Requires
/// time_s >= state->time_s (an earlier time leaves the state unchanged) and a finite state;
/// the caller bounds time_s - state->time_s (EkfOptions::max_prediction_gap_s).
void predictState(EkfState* state, double time_s,
                  const std::array<double, kTunedStateCount>& process_noise_density,
                  double max_step_s, const CalibrationProcess& calibration = {});

}  // namespace gmm_localization
