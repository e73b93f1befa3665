#include "gmm_localization/core/filter/ekf_process_model.h"

#include <algorithm>
#include <cmath>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace {

// cos(pitch) kept away from zero so the Euler-rate map E stays finite (ekf_state.h).
double safeCos(double pitch) {
  constexpr double kMinCos = 1e-6;
  const double c = std::cos(pitch);
  return std::abs(c) < kMinCos ? std::copysign(kMinCos, c) : c;
}

}  // namespace

StateVector predictStep(const StateVector& x, double dt, StateCovariance* jacobian) {
  const double roll = x(kStateRoll), pitch = x(kStatePitch), yaw = x(kStateYaw);
  const Eigen::Vector3d v = x.segment<3>(kLinearVelocityBlock);
  const Eigen::Vector3d w = x.segment<3>(kAngularVelocityBlock);
  const Eigen::Vector3d a = x.segment<3>(kLinearAccelerationBlock);

  const Eigen::Matrix3d rx = Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d ry = Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d rz = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d r = rz * ry * rx;

  // E(roll, pitch): body rates -> Euler-angle rates.
  const double sr = std::sin(roll), cr = std::cos(roll);
  const double cp = safeCos(pitch), sp = std::sin(pitch), tp = sp / cp;
  Eigen::Matrix3d e;
  e << 1.0, sr * tp, cr * tp, 0.0, cr, -sr, 0.0, sr / cp, cr / cp;

  const Eigen::Vector3d d = v * dt + 0.5 * dt * dt * a;  // body-frame displacement
  StateVector out = x;
  out.segment<3>(kPositionBlock) += r * d;
  out.segment<3>(kOrientationBlock) += e * w * dt;
  out.segment<3>(kLinearVelocityBlock) += (a - w.cross(v)) * dt;
  for (int i = kStateRoll; i <= kStateYaw; ++i) out(i) = wrapAngle(out(i));

  if (jacobian != nullptr) {
    StateCovariance& f = *jacobian;
    f.setIdentity();
    // Position w.r.t. the Euler angles: dR/droll = Rz Ry Rx [e1]x, dR/dpitch = Rz Ry [e2]x Rx,
    // dR/dyaw = [e3]x R.
    f.block<3, 1>(kStateX, kStateRoll) = rz * ry * rx * skewSymmetric(Eigen::Vector3d::UnitX()) * d;
    f.block<3, 1>(kStateX, kStatePitch) =
        rz * ry * skewSymmetric(Eigen::Vector3d::UnitY()) * rx * d;
    f.block<3, 1>(kStateX, kStateYaw) = skewSymmetric(Eigen::Vector3d::UnitZ()) * r * d;
    f.block<3, 3>(kStateX, kStateVx) = r * dt;
    f.block<3, 3>(kStateX, kStateAx) = 0.5 * dt * dt * r;
    // Euler angles w.r.t. roll and pitch (through E) and the body rates.
    const double wy = w.y(), wz = w.z();
    const double q = sr * wy + cr * wz;  // appears in several partials
    f(kStateRoll, kStateRoll) += dt * (cr * tp * wy - sr * tp * wz);
    f(kStatePitch, kStateRoll) += dt * (-sr * wy - cr * wz);
    f(kStateYaw, kStateRoll) += dt * (cr * wy - sr * wz) / cp;
    f(kStateRoll, kStatePitch) += dt * q / (cp * cp);
    f(kStateYaw, kStatePitch) += dt * q * sp / (cp * cp);
    f.block<3, 3>(kStateRoll, kStateWx) = e * dt;
    // Body velocity: v' = v + (a - w x v) dt, and w x v = -v x w.
    f.block<3, 3>(kStateVx, kStateVx) -= skewSymmetric(w) * dt;
    f.block<3, 3>(kStateVx, kStateWx) = skewSymmetric(v) * dt;
    f.block<3, 3>(kStateVx, kStateAx) = Eigen::Matrix3d::Identity() * dt;
  }
  return out;
}

void predictState(EkfState* state, double time_s,
                  const std::array<double, kTunedStateCount>& process_noise_density,
                  double max_step_s, const CalibrationProcess& calibration) {
  double remaining = time_s - state->time_s;
  if (!(remaining > 0.0)) return;
  const int steps = std::max(1, static_cast<int>(std::ceil(remaining / max_step_s)));
  const double dt = remaining / steps;
  StateVector q = StateVector::Zero();
  q.head<kTunedStateCount>() =
      Eigen::Map<const Eigen::Matrix<double, kTunedStateCount, 1>>(process_noise_density.data());
  q.segment<3>(kStateGyroBiasX).setConstant(calibration.gyro_bias_density);
  // The GNSS bias's exact discrete Gauss-Markov step (ekf_process_model.h).
  const bool bias_moves = calibration.gnss_bias_tau_s > 0.0;
  const double decay = bias_moves ? std::exp(-dt / calibration.gnss_bias_tau_s) : 1.0;
  const double sigma = calibration.gnss_bias_sigma_m;
  const double bias_var = bias_moves ? (1.0 - decay * decay) * sigma * sigma : 0.0;
  StateCovariance f;
  for (int k = 0; k < steps; ++k) {
    state->x = predictStep(state->x, dt, &f);
    for (int i = kStateGnssBiasX; i <= kStateGnssBiasY; ++i) {
      state->x(i) *= decay;
      f(i, i) = decay;
    }
    state->P = f * state->P * f.transpose();
    state->P.diagonal() += q * dt;
    state->P(kStateGnssBiasX, kStateGnssBiasX) += bias_var;
    state->P(kStateGnssBiasY, kStateGnssBiasY) += bias_var;
  }
  state->P = 0.5 * (state->P + state->P.transpose()).eval();
  state->time_s = time_s;
}

}  // namespace gmm_localization
