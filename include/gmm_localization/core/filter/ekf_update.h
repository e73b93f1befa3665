#pragma once
// The EKF measurement update at one time: innovation, Mahalanobis gate, Joseph-form update.

#include <cmath>
#include <string>

#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

struct UpdateResult {
  enum class Kind { kFused, kRejectedGate, kRejectedNumerical };
  Kind kind = Kind::kRejectedNumerical;
  double mahalanobis_sq = NAN;  ///< NaN when S could not be factorised
  std::string reason;           ///< empty when fused
};

/// Updates state (already predicted to m.stamp_s) with m:
///   nu = z - h(x) (angle components wrapped to [-pi, pi)),  S = H P H^T + R,
///   d^2 = nu^T S^-1 nu; d^2 > gate_threshold_sq rejects (state untouched);
///   K = P H^T S^-1,  x += K nu (angles wrapped),
///   P = (I - K H) P (I - K H)^T + K R K^T (Joseph form, then symmetrised).
/// If S is not positive definite, or x or P would become non-finite or P lose a positive
/// diagonal, the state is left unchanged and kRejectedNumerical is returned with a reason.
UpdateResult applyMeasurement(const EkfMeasurement& m, double gate_threshold_sq,
                              double gravity_mps2, EkfState* state);

}  // namespace gmm_localization
