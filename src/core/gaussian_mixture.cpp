#include "gmm_localization/core/gaussian_mixture.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gmm_localization {
namespace {
constexpr double kHalfLog2Pi = 0.91893853320467274178;  // 0.5 * ln(2 pi)

double componentLog(const GaussianComponent& c, double z) {
  const double s = static_cast<double>(c.sigma_m);
  const double d = (z - static_cast<double>(c.mean_m)) / s;
  return std::log(static_cast<double>(c.weight)) - std::log(s) - kHalfLog2Pi - 0.5 * d * d;
}
}  // namespace

double GaussianMixture1D::logLikelihood(double z_m) const {
  if (count_ == 0) return -std::numeric_limits<double>::infinity();
  std::array<double, kMaxMixtureComponents> terms{};
  double peak = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < count_; ++j) {
    terms[j] = componentLog(components_[j], z_m);
    peak = std::max(peak, terms[j]);
  }
  if (!std::isfinite(peak)) return peak;  // all weights zero, or z at infinity
  double sum = 0.0;
  for (int j = 0; j < count_; ++j) sum += std::exp(terms[j] - peak);
  return peak + std::log(sum);
}

double GaussianMixture1D::maxLogLikelihood(double z_lo, double z_hi) const {
  if (count_ == 0) return -std::numeric_limits<double>::infinity();
  if (count_ == 1) {
    const double mu = components_[0].mean_m;
    return logLikelihood(std::clamp(mu, z_lo, z_hi));
  }
  // The maximum of a mixture lies at an interval end or at a mode. Sample the interval with a
  // step of at most a quarter of the smallest sigma, then refine every sampled local maximum
  // (ends included) by golden-section search over the bracket of its two neighbours.
  double sigma_min = components_[0].sigma_m;
  for (int j = 1; j < count_; ++j) sigma_min = std::min<double>(sigma_min, components_[j].sigma_m);
  const int samples =
      static_cast<int>(std::clamp(std::ceil((z_hi - z_lo) / (0.25 * sigma_min)), 2.0, 4096.0));
  const double step = (z_hi - z_lo) / samples;
  std::vector<double> v(samples + 1);
  for (int i = 0; i <= samples; ++i) v[i] = logLikelihood(z_lo + i * step);
  double best = *std::max_element(v.begin(), v.end());
  constexpr double kInvPhi = 0.61803398874989484820;
  for (int i = 0; i <= samples; ++i) {
    const bool left_ok = i == 0 || v[i] >= v[i - 1];
    const bool right_ok = i == samples || v[i] >= v[i + 1];
    if (!left_ok || !right_ok) continue;
    double a = z_lo + std::max(0, i - 1) * step;
    double b = z_lo + std::min(samples, i + 1) * step;
    for (int it = 0; it < 80 && b - a > 1e-9; ++it) {
      const double c = b - (b - a) * kInvPhi;
      const double d = a + (b - a) * kInvPhi;
      if (logLikelihood(c) > logLikelihood(d)) {
        b = d;
      } else {
        a = c;
      }
    }
    best = std::max(best, logLikelihood(0.5 * (a + b)));
  }
  return best;
}

double GaussianMixture1D::mahalanobis(double z_m) const {
  double best = std::numeric_limits<double>::infinity();
  for (int j = 0; j < count_; ++j) {
    best = std::min(best, std::abs(z_m - components_[j].mean_m) / components_[j].sigma_m);
  }
  return best;
}

bool GaussianMixture1D::operator==(const GaussianMixture1D& o) const {
  if (count_ != o.count_) return false;
  for (int j = 0; j < count_; ++j) {
    const auto& a = components_[j];
    const auto& b = o.components_[j];
    if (a.weight != b.weight || a.mean_m != b.mean_m || a.sigma_m != b.sigma_m) return false;
  }
  return true;
}

}  // namespace gmm_localization
