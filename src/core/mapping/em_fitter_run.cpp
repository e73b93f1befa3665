// EmFitter: deterministic seeding (weighted quantiles, farthest-point) polished by Lloyd steps,
// the EM iterations, and the evaluation of a run (log-likelihood and classification entropy).
#include <algorithm>
#include <cmath>

#include "em_fitter_run.h"

namespace gmm_localization {
namespace {

using em_detail::sortPrefix;
constexpr int kLloydIterations = 20;

/// One EM pass over the samples for K components (K a compile-time constant so the loops
/// unroll): E-step responsibilities by log-sum-exp (the largest term needs no exp), and the
/// M-step sums around the current means, nk = sum w r, s1 = sum w r d, s2 = sum w r d^2.
template <int K>
void emPass(const double* z, const double* w, size_t n, const double* mu, const double* log_norm,
            const double* half_inv_var, double* nk_out, double* s1_out, double* s2_out) {
  double nk[K] = {}, s1[K] = {}, s2[K] = {};  // local, so they stay in registers
  for (size_t i = 0; i < n; ++i) {
    double l[K], d[K];
    int top = 0;
    for (int j = 0; j < K; ++j) {
      d[j] = z[i] - mu[j];
      l[j] = log_norm[j] - d[j] * d[j] * half_inv_var[j];
      if (l[j] > l[top]) top = j;
    }
    const double peak = l[top];
    double sum = 0.0;
    for (int j = 0; j < K; ++j) sum += (l[j] = j == top ? 1.0 : std::exp(l[j] - peak));
    const double w_over_sum = w[i] / sum;
    for (int j = 0; j < K; ++j) {
      const double wr = w_over_sum * l[j];
      nk[j] += wr;
      s1[j] += wr * d[j];
      s2[j] += wr * d[j] * d[j];
    }
  }
  for (int j = 0; j < K; ++j) {
    nk_out[j] = nk[j];
    s1_out[j] = s1[j];
    s2_out[j] = s2[j];
  }
}

}  // namespace

void EmFitter::emRun(Run& run) {
  const size_t n = z_.size();
  const int k = run.k;
  const double var_floor = options_.sigma_floor_m * options_.sigma_floor_m;
  run.valid = false;
  ++counters_.em_runs;
  for (int it = 1; it <= options_.max_iterations; ++it) {
    // One pass: E-step responsibilities r_ij (log-sum-exp; the largest term needs no exp) and
    // the M-step sums around the current means (numerically stable update).
    std::array<double, kMaxMixtureComponents> log_norm{}, half_inv_var{}, nk{}, s1{}, s2{};
    for (int j = 0; j < k; ++j) {
      log_norm[j] = std::log(run.pi[j]) - 0.5 * std::log(run.var[j]);
      half_inv_var[j] = 0.5 / run.var[j];
    }
    if (k == 2) {
      emPass<2>(z_.data(), w_.data(), n, run.mu.data(), log_norm.data(), half_inv_var.data(),
                nk.data(), s1.data(), s2.data());
    } else {
      emPass<3>(z_.data(), w_.data(), n, run.mu.data(), log_norm.data(), half_inv_var.data(),
                nk.data(), s1.data(), s2.data());
    }
    double change = 0.0;
    for (int j = 0; j < k; ++j) {
      if (!(nk[j] > 1e-12)) return;  // collapsed component: this K is not supported
      const double shift = s1[j] / nk[j];
      const double var = std::max(s2[j] / nk[j] - shift * shift, var_floor);
      const double sigma = std::sqrt(run.var[j]);
      change = std::max({change, std::abs(shift) / sigma, std::abs(std::sqrt(var) - sigma) / sigma,
                         std::abs(nk[j] - run.pi[j])});
      run.mu[j] += shift;
      run.var[j] = var;
      run.pi[j] = nk[j];
    }
    run.iterations = it;
    ++counters_.iterations;
    if (!(change >= options_.tolerance)) break;  // converged (or not finite: caught below)
  }
  evaluate(run);
}

void EmFitter::evaluate(Run& run) const {
  // ll = sum_i w_i log p(z_i) and the classification entropy sum_i w_i H(r_i), using
  // -log r_ij = log(sum) - (l_ij - l_top): no log per component.
  const int k = run.k;
  std::array<double, kMaxMixtureComponents> log_norm{}, half_inv_var{};
  for (int j = 0; j < k; ++j) {
    log_norm[j] = std::log(run.pi[j]) - 0.5 * std::log(run.var[j]) - kHalfLog2Pi;
    half_inv_var[j] = 0.5 / run.var[j];
  }
  double ll = 0.0, entropy = 0.0;
  for (size_t i = 0; i < z_.size(); ++i) {
    std::array<double, kMaxMixtureComponents> l{};
    int top = 0;
    for (int j = 0; j < k; ++j) {
      const double d = z_[i] - run.mu[j];
      l[j] = log_norm[j] - d * d * half_inv_var[j];
      if (l[j] > l[top]) top = j;
    }
    double sum = 0.0, weighted_gap = 0.0;
    for (int j = 0; j < k; ++j) {
      const double e = j == top ? 1.0 : std::exp(l[j] - l[top]);
      sum += e;
      weighted_gap += e * (l[j] - l[top]);
    }
    const double log_sum = std::log(sum);
    ll += w_[i] * (l[top] + log_sum);
    entropy += w_[i] * (log_sum - weighted_gap / sum);
  }
  run.ll = ll;
  run.entropy = std::max(entropy, 0.0);
  run.valid = std::isfinite(ll) && std::isfinite(entropy);
  for (int j = 0; j < k; ++j)
    run.valid = run.valid && std::isfinite(run.mu[j]) && std::isfinite(run.var[j]);
}

bool EmFitter::runK(int k, Run& best) {
  const size_t n = z_.size();
  const double var_floor = options_.sigma_floor_m * options_.sigma_floor_m;
  best = Run();
  best.k = k;
  if (k == 1) {
    // Closed form: the weighted mean and variance are the EM fixed point.
    double mu = 0.0;
    for (size_t i = 0; i < n; ++i) mu += w_[i] * z_[i];
    double var = 0.0;
    for (size_t i = 0; i < n; ++i) var += w_[i] * (z_[i] - mu) * (z_[i] - mu);
    best.pi[0] = 1.0;
    best.mu[0] = mu;
    best.var[0] = std::max(var, var_floor);
    evaluate(best);
    return best.valid;
  }
  // Need at least k distinct heights.
  int distinct = 1;
  for (size_t i = 1; i < n && distinct < k; ++i) {
    if (z_[i] > z_[i - 1]) ++distinct;
  }
  if (distinct < k) return false;

  bool found = false;
  std::array<double, kMaxMixtureComponents> first_centres{};
  for (int seeding = 0; seeding < 2; ++seeding) {
    std::array<double, kMaxMixtureComponents> c{};
    if (seeding == 0) {
      // Weighted quantiles (j + 0.5) / k.
      double cum = 0.0;
      int j = 0;
      for (size_t i = 0; i < n && j < k; ++i) {
        cum += w_[i];
        while (j < k && cum >= (j + 0.5) / k) c[j++] = z_[i];
      }
      for (; j < k; ++j) c[j] = z_[n - 1];
    } else {
      // Greedy farthest-point seeding: weighted median, then argmax w * D^2.
      double cum = 0.0;
      size_t med = n - 1;
      for (size_t i = 0; i < n; ++i) {
        cum += w_[i];
        if (cum >= 0.5) {
          med = i;
          break;
        }
      }
      c[0] = z_[med];
      for (int j = 1; j < k; ++j) {
        double best_score = -1.0;
        for (size_t i = 0; i < n; ++i) {
          double d2 = std::numeric_limits<double>::infinity();
          for (int m = 0; m < j; ++m) d2 = std::min(d2, (z_[i] - c[m]) * (z_[i] - c[m]));
          if (w_[i] * d2 > best_score) {
            best_score = w_[i] * d2;
            c[j] = z_[i];
          }
        }
      }
      sortPrefix(c, k, [](double a, double b) { return a < b; });
    }
    // Weighted Lloyd steps; then initial EM parameters from the hard clusters.
    std::array<double, kMaxMixtureComponents> cw{}, cz{}, czz{};
    for (int iter = 0; iter < kLloydIterations; ++iter) {
      cw.fill(0.0);
      cz.fill(0.0);
      czz.fill(0.0);
      for (size_t i = 0; i < n; ++i) {
        int nearest = 0;
        for (int m = 1; m < k; ++m) {
          if (std::abs(z_[i] - c[m]) < std::abs(z_[i] - c[nearest])) nearest = m;
        }
        cw[nearest] += w_[i];
        cz[nearest] += w_[i] * z_[i];
        czz[nearest] += w_[i] * z_[i] * z_[i];
      }
      bool moved = false;
      for (int m = 0; m < k; ++m) {
        if (cw[m] <= 0.0) continue;
        const double nc = cz[m] / cw[m];
        moved = moved || nc != c[m];
        c[m] = nc;
      }
      if (!moved) break;
    }
    // Both seedings often reach the same partition: EM would repeat the same run.
    if (seeding == 0) {
      first_centres = c;
    } else {
      bool same = true;
      for (int m = 0; m < k; ++m) same = same && std::abs(c[m] - first_centres[m]) <= 1e-9;
      if (same) break;
    }
    Run run;
    run.k = k;
    double total_var = 0.0;
    for (size_t i = 0; i < n; ++i) total_var += w_[i] * z_[i] * z_[i];  // z_ has mean 0
    for (int m = 0; m < k; ++m) {
      run.mu[m] = c[m];
      if (cw[m] > 1e-9) {
        run.pi[m] = cw[m];
        run.var[m] = std::max(czz[m] / cw[m] - c[m] * c[m], var_floor);
      } else {
        run.pi[m] = 1e-3;
        run.var[m] = std::max(total_var, var_floor);
      }
    }
    double pi_sum = 0.0;
    for (int m = 0; m < k; ++m) pi_sum += run.pi[m];
    for (int m = 0; m < k; ++m) run.pi[m] /= pi_sum;
    emRun(run);
    if (run.valid && (!found || run.ll > best.ll)) {
      best = run;
      found = true;
    }
  }
  return found;
}

}  // namespace gmm_localization
