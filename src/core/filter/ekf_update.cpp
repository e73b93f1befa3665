#include "gmm_localization/core/filter/ekf_update.h"

#include <sstream>

#include <Eigen/Cholesky>

namespace gmm_localization {

UpdateResult applyMeasurement(const EkfMeasurement& m, double gate_threshold_sq,
                              double gravity_mps2, EkfState* state) {
  UpdateResult result;
  if (m.model == MeasurementModel::kCovarianceFloor) {
    for (int i = 0; i < m.size; ++i) {
      const int k = m.indices[i];
      const double v = std::max(state->P(k, k), m.z(i));
      state->P.row(k).setZero();
      state->P.col(k).setZero();
      state->P(k, k) = v;
    }
    result.kind = UpdateResult::Kind::kFused;
    return result;
  }
  MeasurementVector h;
  MeasurementJacobian H;
  evaluateMeasurement(m, state->x, gravity_mps2, &h, &H);
  MeasurementVector nu = m.z - h;
  for (int i = 0; i < m.size; ++i) {
    if (m.model == MeasurementModel::kDirect && isAngleState(m.indices[i])) {
      nu(i) = wrapAngle(nu(i));
    }
  }

  // P H^T is all the update needs from P: (kStateSize x m).
  const Eigen::Matrix<double, kStateSize, Eigen::Dynamic, 0, kStateSize, kMaxMeasurementSize> pht =
      state->P * H.transpose();
  MeasurementCovariance s = H * pht + m.R;
  s = 0.5 * (s + s.transpose()).eval();
  Eigen::LLT<MeasurementCovariance> llt(s);
  if (llt.info() != Eigen::Success || !s.allFinite()) {
    result.reason = "innovation covariance is not positive definite";
    return result;
  }
  result.mahalanobis_sq = nu.dot(llt.solve(nu));
  if (std::isnan(result.mahalanobis_sq)) {
    result.reason = "Mahalanobis distance is not a number";
    return result;
  }
  if (result.mahalanobis_sq > gate_threshold_sq) {
    std::ostringstream why;
    why << "Mahalanobis distance " << std::sqrt(result.mahalanobis_sq) << " exceeds the gate "
        << std::sqrt(gate_threshold_sq) << " (d^2 " << result.mahalanobis_sq << " > "
        << gate_threshold_sq << ", " << m.size << " dof)";
    result.kind = UpdateResult::Kind::kRejectedGate;
    result.reason = why.str();
    return result;
  }

  // K = P H^T S^-1, computed as (S^-1 (P H^T)^T)^T since S is symmetric.
  const Eigen::Matrix<double, kStateSize, Eigen::Dynamic, 0, kStateSize, kMaxMeasurementSize> k =
      llt.solve(pht.transpose()).transpose();
  StateVector x = state->x + k * nu;
  for (int i = kStateRoll; i <= kStateYaw; ++i) x(i) = wrapAngle(x(i));
  const StateCovariance i_kh = StateCovariance::Identity() - k * H;
  StateCovariance p = i_kh * state->P * i_kh.transpose() + k * m.R * k.transpose();
  p = 0.5 * (p + p.transpose()).eval();
  if (!x.allFinite() || !p.allFinite() || (p.diagonal().array() <= 0.0).any()) {
    result.reason = "update would make the state non-finite or its covariance not positive";
    return result;
  }
  state->x = x;
  state->P = p;
  result.kind = UpdateResult::Kind::kFused;
  return result;
}

}  // namespace gmm_localization
