#pragma once
// Weighted EM for a 1-D Gaussian mixture over z-height, with model selection over the number of
// components (paper section III: "we re-run the EM for a varying number of Gaussians, choosing
// the resulting Gaussian mixture with the greatest likelihood without overfitting").
//
// Input: weighted samples. A sample aggregates one or more observations (LIDAR returns) at the
// same height: `weight` is the sum of their weights (the builder's blur-kernel weights, times
// the count when a z-histogram bin holds several returns) and `weight_sq` the sum of their
// squared weights. `weight_sq` is what lets the fitter tell 100 returns in one bin (strong
// evidence) from one return with weight 100 (weak evidence).
//
// Effective sample size. The number n in the BIC penalty is Kish's effective sample size of the
// underlying observations, n = (sum w)^2 / (sum w^2), summed over observations, i.e.
// n = W^2 / sum(weight_sq). For unit weights it is the number of returns; for a histogram bin
// of c returns with kernel weight k it contributes c*k to W and c*k^2 to the denominator, so
// blurred-in returns from neighbouring columns count as partial observations and a histogram
// counts its returns, not its bins. The weighted log-likelihood sum_i w_i log p(z_i) is rescaled
// by n / W so that it is on the scale of n independent observations (the usual pseudo-likelihood
// treatment of weighted data) before it enters the criterion.
//
// Model selection (option `criterion`):
//  - kIcl (default): ICL-BIC (Biernacki, Celeux, Govaert 2000) = BIC + 2 * n/W * sum_i w_i *
//    H(r_i), where H(r_i) is the entropy of sample i's component responsibilities. BIC alone
//    estimates the number of Gaussians needed to approximate the density and, with the
//    thousands of returns of a dense map cell, splits any non-Gaussian mode (a wall's uniform
//    height spread, a ground cell's noise tail) into several heavily overlapping components.
//    ICL charges for that overlap, so it selects separated modes (ground, overhang, canopy),
//    which is what the paper's maps show: a tight ground Gaussian and wide superstructure ones.
//    For well-separated components the entropy term is ~0 and ICL equals BIC.
//  - kBic: BIC = -2 * n/W * LL_w + p ln n, p = 3K - 1 free parameters.
// The smallest criterion wins; ties go to fewer components. A K is only eligible when every
// component keeps at least `min_samples_per_component` effective observations and at least
// `min_component_weight` of the mixing weight.
//
// Determinism: no random numbers. For each K >= 2 EM starts from two deterministic seedings,
// (a) weighted quantiles and (b) greedy farthest-point seeding (weighted median first, then the
// sample maximising w * D^2), each polished by weighted Lloyd (k-means) steps; the run with the
// larger final log-likelihood is kept. Results do not depend on the input order up to
// floating-point summation order (the fitter sorts its input by z).
//
// Variance floor: every sigma is at least `sigma_floor_m` (default 0.03 m: a LIDAR's ~2 cm
// range noise combined in quadrature with ~2 cm of map pose and discretisation error). This is
// what keeps one point, or all points at one height, from producing a zero-width Gaussian.
//
// Failure behaviour: never throws, never returns NaN. Non-finite samples and samples with
// weight <= 0 are ignored; when nothing usable remains the result is an empty mixture with a
// reason. Thread safety: a fitter holds scratch buffers; use one instance per thread.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "gmm_localization/core/map/gaussian_mixture.h"

namespace gmm_localization {

/// A z value with the summed weight (and summed squared weight) of the observations it stands for.
struct WeightedSample {
  double z_m = 0.0;        ///< height in the map frame [m]
  double weight = 1.0;     ///< sum of the observations' weights, > 0
  double weight_sq = 1.0;  ///< sum of the observations' squared weights, > 0 (weight^2 for one)
};

enum class ModelSelection { kIcl, kBic };

struct EmFitterOptions {
  int max_components = 2;       ///< K_max, in [1, kMaxMixtureComponents]
  double sigma_floor_m = 0.03;  ///< smallest standard deviation [m], in [1e-4, 10]
  int max_iterations = 100;     ///< EM iterations per run, in [1, 10000]
  double tolerance = 1e-3;      ///< EM stops when no mean moves by more than this
                                ///< times its sigma, no sigma changes by more than
                                ///< this fraction and no weight by more than this;
                                ///< in (0, 1)
  ModelSelection criterion = ModelSelection::kIcl;
  double min_samples_per_component = 3.0;  ///< effective observations per component, >= 0
  double min_component_weight = 1e-3;      ///< smallest mixing weight, in [1e-6, 0.5)

  /// Empty when valid, else the first offending field, its value and the allowed range.
  std::string validate() const;
};

/// Outcome of one fit. `mixture` is empty (and `reason` says why) when there was no usable data.
struct EmFitResult {
  GaussianMixture1D mixture;       ///< components sorted by ascending mean
  std::string reason;              ///< empty on success
  double effective_samples = 0.0;  ///< Kish n = W^2 / sum(weight_sq)
  double total_weight = 0.0;       ///< W over the usable samples
  double log_likelihood = 0.0;     ///< sum_i w_i log p(z_i) of the chosen mixture [nats]
  double criterion_value = 0.0;    ///< ICL or BIC of the chosen mixture
  int iterations = 0;              ///< EM iterations spent on the chosen K
};

/// Work done by a fitter since construction (diagnostics and benchmarks).
struct EmFitterCounters {
  uint64_t fits = 0;        ///< fit()/fitFixed() calls with usable data
  uint64_t em_runs = 0;     ///< EM runs (K >= 2, per seeding)
  uint64_t iterations = 0;  ///< EM iterations over all runs
  uint64_t samples = 0;     ///< usable samples over all fits
};

class EmFitter {
 public:
  /// Options must be valid (validate() empty); invalid options are clamped into range.
  explicit EmFitter(const EmFitterOptions& options = EmFitterOptions());

  const EmFitterOptions& options() const { return options_; }
  const EmFitterCounters& counters() const { return counters_; }

  /// Fits the mixture with model selection over K = 1..max_components.
  EmFitResult fit(const std::vector<WeightedSample>& samples);
  EmFitResult fit(const WeightedSample* samples, size_t count);

  /// Fits exactly K components (no model selection); K is clamped to [1, max_components]. When
  /// the data cannot support K components (too few distinct heights, a collapsed component) the
  /// result has fewer components. Exposed for tests and diagnostics.
  EmFitResult fitFixed(const WeightedSample* samples, size_t count, int components);

 private:
  struct Run;  // one EM run's parameters and statistics (em_fitter.cpp)

  bool prepare(const WeightedSample* samples, size_t count, EmFitResult& result);
  bool runK(int k, Run& best);
  void emRun(Run& run);
  void evaluate(Run& run) const;
  double criterion(const Run& run) const;
  void fillResult(const Run& run, EmFitResult& result) const;

  EmFitterOptions options_;
  EmFitterCounters counters_;
  // Scratch, reused between fits: the usable samples sorted by z, shifted by z_offset_.
  std::vector<double> z_, w_;
  std::vector<std::pair<double, double>> zw_;  // (z, w) while sorting
  double z_offset_ = 0.0;
  double total_w_ = 0.0;
  double n_eff_ = 0.0;
};

const char* toString(ModelSelection m);

}  // namespace gmm_localization
