#include "gmm_localization/core/map/gaussian_mixture.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace gmm_localization {
namespace {

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

PreparedMixture::PreparedMixture(const GaussianMixture1D& g) : n_(g.size()) {
  for (int j = 0; j < n_; ++j) {
    const GaussianComponent& c = g.component(j);
    mean_[j] = c.mean_m;
    sigma_[j] = c.sigma_m;
    norm_[j] = std::log(static_cast<double>(c.weight)) - std::log(sigma_[j]) - kHalfLog2Pi;
  }
}

std::vector<double> GaussianMixture1D::modes() const {
  std::vector<double> result;
  if (count_ == 0) return result;
  if (count_ == 1) {
    result.push_back(components_[0].mean_m);
    return result;
  }
  double lo = components_[0].mean_m, hi = lo, sigma_min = components_[0].sigma_m;
  for (int j = 1; j < count_; ++j) {
    lo = std::min<double>(lo, components_[j].mean_m);
    hi = std::max<double>(hi, components_[j].mean_m);
    sigma_min = std::min<double>(sigma_min, components_[j].sigma_m);
  }
  // Outside [lo, hi] every component pulls towards the interval, so no mode lies there.
  const int samples =
      static_cast<int>(std::clamp(std::ceil((hi - lo) / (0.25 * sigma_min)), 2.0, 1.0e5));
  const double step = (hi - lo) / samples;
  const PreparedMixture p(*this);  // logLikelihood without its logs per call
  std::vector<double> v(samples + 1);
  for (int i = 0; i <= samples; ++i) v[i] = p.logLikelihood(lo + i * step);
  constexpr double kInvPhi = 0.61803398874989484820;
  for (int i = 0; i <= samples; ++i) {
    const bool rises_to = i == 0 || v[i] > v[i - 1];
    const bool falls_after = i == samples || v[i] >= v[i + 1];
    if (!rises_to || !falls_after) continue;
    double a = lo + std::max(0, i - 1) * step;
    double b = lo + std::min(samples, i + 1) * step;
    for (int it = 0; it < 100 && b - a > 1e-9; ++it) {
      const double c = b - (b - a) * kInvPhi;
      const double d = a + (b - a) * kInvPhi;
      if (p.logLikelihood(c) > p.logLikelihood(d)) {
        b = d;
      } else {
        a = c;
      }
    }
    result.push_back(0.5 * (a + b));
  }
  return result;
}

double GaussianMixture1D::maxLogLikelihood(double z_lo, double z_hi) const {
  return maxLogLikelihood(z_lo, z_hi, modes());
}

double GaussianMixture1D::maxLogLikelihood(double z_lo, double z_hi,
                                           const std::vector<double>& modes) const {
  if (count_ == 0) return -std::numeric_limits<double>::infinity();
  const PreparedMixture p(*this);
  double best = std::max(p.logLikelihood(z_lo), p.logLikelihood(z_hi));
  for (double m : modes) {
    if (m > z_lo && m < z_hi) best = std::max(best, p.logLikelihood(m));
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

MixtureLogTerms::MixtureLogTerms(const GaussianMixture1D& g) {
  count = static_cast<uint8_t>(g.size());
  for (int j = 0; j < g.size(); ++j) {
    const GaussianComponent& c = g.component(j);
    mean[j] = c.mean_m;
    inv_sigma[j] = 1.0f / c.sigma_m;
    log_norm[j] = static_cast<float>(std::log(static_cast<double>(c.weight)) -
                                     std::log(static_cast<double>(c.sigma_m)) - kHalfLog2Pi);
  }
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

bool MixtureLogTerms::logTerms(double z_m, double* t, double* peak) const {
  *peak = -std::numeric_limits<double>::infinity();
  int top = 0;
  for (int j = 0; j < count; ++j) {
    const double d = (z_m - mean[j]) * inv_sigma[j];
    t[j] = log_norm[j] - 0.5 * d * d;
    if (t[j] > *peak) {
      *peak = t[j];
      top = j;
    }
  }
  if (count == 1 || !std::isfinite(*peak)) return true;
  // exp(-40) = 4.2e-18: two such terms, summed before or after the peak's exp(0) = 1, leave
  // the double sum at exactly 1 (half an ulp of 1 is 1.1e-16), and log(1) = 0.
  constexpr double kNegligible = -40.0;
  for (int j = 0; j < count; ++j) {
    if (j != top && t[j] - *peak >= kNegligible) return false;
  }
  return true;
}

double MixtureLogTerms::logSumExp(const double* t, double peak) const {
  double sum = 0.0;
  // The peak's own term is exp(0) = 1 exactly: added without calling exp, the same sum.
  for (int j = 0; j < count; ++j) sum += t[j] == peak ? 1.0 : std::exp(t[j] - peak);
  return peak + std::log(sum);
}

double MixtureLogTerms::logLikelihood(double z_m) const {
  if (count == 0) return -std::numeric_limits<double>::infinity();
  double t[kMaxMixtureComponents], peak;
  if (logTerms(z_m, t, &peak)) return peak;
  return logSumExp(t, peak);
}

double MixtureLogTerms::flooredLogLikelihood(double z_m, double floor) const {
  if (count == 0) return floor;
  double t[kMaxMixtureComponents], peak;
  if (logTerms(z_m, t, &peak)) return std::max(floor, peak);
  // The sum of at most three terms of at most 1 each: the value is at most peak + log(3)
  // (1.0986); below the floor by more than that (with room for rounding) it is the floor.
  static_assert(kMaxMixtureComponents <= 3, "the bound below is log(3)");
  if (peak + 1.1 < floor) return floor;
  return std::max(floor, logSumExp(t, peak));
}

}  // namespace gmm_localization
