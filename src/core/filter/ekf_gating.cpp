#include "gmm_localization/core/filter/ekf_gating.h"

#include <cmath>
#include <limits>

namespace gmm_localization {

double chiSquareUpperTail(double x, int dof) {
  if (!(x > 0.0)) return 1.0;
  if (std::isinf(x)) return 0.0;
  const double h = 0.5 * x;
  // Q(a + 1, h) = Q(a, h) + h^a e^-h / Gamma(a + 1), starting from Q(1/2, h) = erfc(sqrt h)
  // (odd dof) or Q(1, h) = e^-h (even dof).
  double a = (dof % 2 == 1) ? 0.5 : 1.0;
  double q = (dof % 2 == 1) ? std::erfc(std::sqrt(h)) : std::exp(-h);
  // term_a = h^a e^-h / Gamma(a + 1), updated by term_{a+1} = term_a * h / (a + 1).
  double term = std::exp(a * std::log(h) - h - std::lgamma(a + 1.0));
  while (a + 1e-9 < 0.5 * dof) {
    q += term;
    a += 1.0;
    term *= h / a;
  }
  return q;
}

double chiSquareQuantile(double p, int dof) {
  if (!(p > 0.0)) return 0.0;
  if (!(p < 1.0)) return std::numeric_limits<double>::infinity();
  const double tail = 1.0 - p;
  double lo = 0.0, hi = dof + 10.0;
  while (chiSquareUpperTail(hi, dof) > tail) hi *= 2.0;
  while (hi - lo > 1e-10 * hi) {
    const double mid = 0.5 * (lo + hi);
    (chiSquareUpperTail(mid, dof) > tail ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace gmm_localization
