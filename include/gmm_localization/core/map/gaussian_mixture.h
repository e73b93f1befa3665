#pragma once
// One map cell's model: a 1-D Gaussian mixture over z-height (paper section III, Eq. 1).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace gmm_localization {

/// Largest number of components a cell can hold. The paper (and our default) uses at most two;
/// three is allowed for dense vegetation experiments.
constexpr int kMaxMixtureComponents = 3;
/// 0.5 * ln(2 pi): the normalizer of a 1-D Gaussian's log density.
constexpr double kHalfLog2Pi = 0.91893853320467274178;

struct GaussianComponent {
  float weight = 0.f;   ///< mixing weight in (0, 1]; a cell's weights sum to 1
  float mean_m = 0.f;   ///< mean height in the map frame [m]
  float sigma_m = 1.f;  ///< standard deviation [m], > 0
};

/// Mixture p(z) = sum_j w_j N(z; mu_j, sigma_j^2). Empty means "no map data in this cell".
class GaussianMixture1D {
 public:
  GaussianMixture1D() = default;

  int size() const { return count_; }
  bool empty() const { return count_ == 0; }
  const GaussianComponent& component(int j) const { return components_[j]; }
  GaussianComponent& component(int j) { return components_[j]; }

  /// Appends a component; returns false (and changes nothing) when already full.
  bool add(const GaussianComponent& c) {
    if (count_ >= kMaxMixtureComponents) return false;
    components_[count_++] = c;
    return true;
  }
  void clear() { count_ = 0; }

  /// log p(z) with the standard normal density (Eq. 1 of the paper, whose printed exponent lacks
  /// the 1/2 of a normal density; we use the density). Computed with log-sum-exp so it never
  /// overflows; returns -infinity for an empty mixture. Requires sigma_m > 0 for all components.
  double logLikelihood(double z_m) const;

  /// Local maxima of p(z), ascending. One component: its mean. Several: every mode lies between
  /// the extreme means; they are found by a scan at a quarter of the smallest sigma, each sampled
  /// local maximum refined by golden-section search. Empty for an empty mixture.
  std::vector<double> modes() const;

  /// Largest value of log p(z) over z in [z_lo, z_hi] (z_lo <= z_hi): the max over the interval
  /// ends and the modes inside it. Returns -infinity for an empty mixture.
  double maxLogLikelihood(double z_lo, double z_hi) const;
  /// The same with the modes already computed (rasterization calls it per z bin).
  double maxLogLikelihood(double z_lo, double z_hi, const std::vector<double>& modes) const;

  /// Mahalanobis distance of z to the nearest component, |z - mu_j| / sigma_j minimised over j
  /// (infinity for an empty mixture). Used by the obstacle classifier (paper V-C).
  double mahalanobis(double z_m) const;

  bool operator==(const GaussianMixture1D& o) const;

 private:
  std::array<GaussianComponent, kMaxMixtureComponents> components_{};
  uint8_t count_ = 0;
};

/// GaussianMixture1D::logLikelihood, bit for bit, with each component's log(w / sigma) -
/// log(sqrt(2 pi)) computed once instead of per call (the same double operations in the same
/// order): for the many evaluations of one mixture in modes() and in rasterization.
class PreparedMixture {
 public:
  explicit PreparedMixture(const GaussianMixture1D& g);
  double logLikelihood(double z_m) const {
    double t[kMaxMixtureComponents];
    double peak = -std::numeric_limits<double>::infinity();
    for (int j = 0; j < n_; ++j) {
      const double d = (z_m - mean_[j]) / sigma_[j];
      t[j] = norm_[j] - 0.5 * d * d;
      peak = std::max(peak, t[j]);
    }
    if (n_ <= 1 || !std::isfinite(peak)) return peak;  // log(exp(0)) = 0: the same for one
    double sum = 0.0;
    for (int j = 0; j < n_; ++j) sum += std::exp(t[j] - peak);
    return peak + std::log(sum);
  }

 private:
  int n_ = 0;
  double mean_[kMaxMixtureComponents] = {}, sigma_[kMaxMixtureComponents] = {};
  double norm_[kMaxMixtureComponents] = {};
};

/// A mixture prepared for fast repeated evaluation: per component the mean, 1/sigma and
/// log(w / (sigma sqrt(2 pi))), so one component costs a multiply-add and two an exp and a log.
struct MixtureLogTerms {
  uint8_t count = 0;
  std::array<float, kMaxMixtureComponents> mean{};
  std::array<float, kMaxMixtureComponents> inv_sigma{};
  std::array<float, kMaxMixtureComponents> log_norm{};

  MixtureLogTerms() = default;
  explicit MixtureLogTerms(const GaussianMixture1D& g);
  /// Same value as GaussianMixture1D::logLikelihood (to float precision); -inf when empty.
  /// The exp and the log are skipped when every other component is negligible beside the
  /// nearest (the sum is then exactly 1): the same value, bit for bit, as computing them.
  double logLikelihood(double z_m) const;
  /// max(floor, logLikelihood(z_m)), bit for bit, without the exp and the log when the nearest
  /// component alone puts the mixture below the floor (its log-density + log(count) < floor).
  double flooredLogLikelihood(double z_m, double floor) const;

 private:
  /// The components' log-densities at z_m into t, their maximum into *peak; true when the
  /// mixture's value is *peak exactly (one component, a non-finite peak, or every other term
  /// below exp(-40): added to the peak's 1 they change no bit of the sum).
  bool logTerms(double z_m, double* t, double* peak) const;
  /// peak + log(sum of exp(t_j - peak)), the terms summed in component order.
  double logSumExp(const double* t, double peak) const;
};

}  // namespace gmm_localization
