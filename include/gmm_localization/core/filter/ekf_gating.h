#pragma once
// Chi-square quantities for Mahalanobis gating of EKF innovations.
//
// For a consistent filter, the squared Mahalanobis distance d^2 = nu^T S^-1 nu of an m-dimensional
// innovation nu with covariance S follows a chi-square distribution with m degrees of freedom.
// A gate that accepts probability p rejects d^2 > chiSquareQuantile(p, m).

namespace gmm_localization {

/// Upper tail Q(x; k) = P[X > x] of a chi-square variable with k >= 1 degrees of freedom, from
/// the regularized upper incomplete gamma Q(k/2, x/2) by its closed form for integer and
/// half-integer order (a sum of positive terms: accurate deep into the tail). x <= 0 gives 1.
double chiSquareUpperTail(double x, int dof);

/// Smallest x with P[X <= x] >= p for X ~ chi-square(dof), by bisection to 1e-10 relative.
/// p in (0, 1); p >= 1 gives +infinity (no gate), p <= 0 gives 0; dof >= 1.
double chiSquareQuantile(double p, int dof);

}  // namespace gmm_localization
