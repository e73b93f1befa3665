#include "gmm_localization/core/mapping/em_fitter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "em_fitter_run.h"

namespace gmm_localization {
namespace {

using em_detail::sortPrefix;

// Heights beyond this are not physical map data; such samples are ignored so that squared
// deviations can never overflow.
constexpr double kMaxAbsSampleHeightM = 1.0e9;

std::string fieldError(const char* name, double value, const char* range) {
  std::ostringstream s;
  s << name << "=" << value << " must be in " << range;
  return s.str();
}
}  // namespace

const char* toString(ModelSelection m) { return m == ModelSelection::kBic ? "bic" : "icl"; }

std::string EmFitterOptions::validate() const {
  if (max_components < 1 || max_components > kMaxMixtureComponents) {
    return fieldError("max_components", max_components, "[1, kMaxMixtureComponents=3]");
  }
  if (!(sigma_floor_m >= 1e-4 && sigma_floor_m <= 10.0)) {
    return fieldError("sigma_floor_m", sigma_floor_m, "[1e-4, 10] m");
  }
  if (max_iterations < 1 || max_iterations > 10000) {
    return fieldError("max_iterations", max_iterations, "[1, 10000]");
  }
  if (!(tolerance > 0.0 && tolerance < 1.0)) return fieldError("tolerance", tolerance, "(0, 1)");
  if (!(min_samples_per_component >= 0.0 && std::isfinite(min_samples_per_component))) {
    return fieldError("min_samples_per_component", min_samples_per_component, "[0, inf)");
  }
  if (!(min_component_weight >= 1e-6 && min_component_weight < 0.5)) {
    return fieldError("min_component_weight", min_component_weight, "[1e-6, 0.5)");
  }
  return {};
}

EmFitter::EmFitter(const EmFitterOptions& options) : options_(options) {
  options_.max_components = std::clamp(options_.max_components, 1, kMaxMixtureComponents);
  if (!(options_.sigma_floor_m >= 1e-4)) options_.sigma_floor_m = 1e-4;
  options_.max_iterations = std::clamp(options_.max_iterations, 1, 10000);
  if (!(options_.tolerance > 0.0)) options_.tolerance = 1e-3;
  if (!(options_.min_component_weight >= 1e-6)) options_.min_component_weight = 1e-6;
  if (!(options_.min_samples_per_component >= 0.0)) options_.min_samples_per_component = 0.0;
}

EmFitResult EmFitter::fit(const std::vector<WeightedSample>& samples) {
  return fit(samples.data(), samples.size());
}

bool EmFitter::prepare(const WeightedSample* samples, size_t count, EmFitResult& result) {
  z_.clear();
  w_.clear();
  std::vector<std::pair<double, double>>& zw = zw_;
  zw.clear();
  double w_max = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const WeightedSample& s = samples[i];
    if (!std::isfinite(s.z_m) || std::abs(s.z_m) > kMaxAbsSampleHeightM) continue;
    if (!std::isfinite(s.weight) || !(s.weight > 0.0)) continue;
    w_max = std::max(w_max, s.weight);
  }
  if (!(w_max > 0.0)) {
    result.reason =
        count == 0 ? "no samples" : "zero total weight (no finite sample with weight > 0)";
    return false;
  }
  // Normalise by the largest weight first, then by the total, so no sum can overflow.
  double sum_w = 0.0, sum_wsq = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const WeightedSample& s = samples[i];
    if (!std::isfinite(s.z_m) || std::abs(s.z_m) > kMaxAbsSampleHeightM) continue;
    if (!std::isfinite(s.weight) || !(s.weight > 0.0)) continue;
    const double w = s.weight / w_max;
    // A consistent weight_sq lies in (0, weight^2]; anything else is treated as one observation.
    double wsq = s.weight_sq / (w_max * w_max);
    if (!std::isfinite(wsq) || !(wsq > 0.0) || wsq > w * w) wsq = w * w;
    sum_w += w;
    sum_wsq += wsq;
    zw.emplace_back(s.z_m, w);
  }
  std::sort(zw.begin(), zw.end());
  // Kish's effective sample size of the underlying observations (see header).
  n_eff_ = sum_w * sum_w / std::max(sum_wsq, std::numeric_limits<double>::min());
  if (!std::isfinite(n_eff_) || n_eff_ < 1.0) n_eff_ = 1.0;
  total_w_ = sum_w * w_max;
  double mean = 0.0;
  for (const auto& [z, w] : zw) mean += (w / sum_w) * z;
  z_offset_ = mean;
  z_.reserve(zw.size());
  w_.reserve(zw.size());
  for (const auto& [z, w] : zw) {
    z_.push_back(z - z_offset_);
    w_.push_back(w / sum_w);
  }
  ++counters_.fits;
  counters_.samples += z_.size();
  result.total_weight = std::isfinite(total_w_) ? total_w_ : std::numeric_limits<double>::max();
  result.effective_samples = n_eff_;
  return true;
}

double EmFitter::criterion(const Run& run) const {
  // Weights are normalised to sum 1, so n/W scaling (see header) is a factor n_eff_.
  const double params = 3.0 * run.k - 1.0;
  double c = -2.0 * n_eff_ * run.ll + params * std::log(std::max(n_eff_, 1.0));
  if (options_.criterion == ModelSelection::kIcl) c += 2.0 * n_eff_ * run.entropy;
  return c;
}

void EmFitter::fillResult(const Run& run, EmFitResult& result) const {
  std::array<int, kMaxMixtureComponents> order{0, 1, 2};
  sortPrefix(order, run.k, [&](int a, int b) { return run.mu[a] < run.mu[b]; });
  result.mixture.clear();
  for (int m = 0; m < run.k; ++m) {
    const int j = order[m];
    GaussianComponent c;
    c.weight = static_cast<float>(run.pi[j]);
    c.mean_m = static_cast<float>(run.mu[j] + z_offset_);
    c.sigma_m = static_cast<float>(std::sqrt(run.var[j]));
    result.mixture.add(c);
  }
  result.log_likelihood = run.ll * total_w_;
  result.criterion_value = criterion(run);
  result.iterations = run.iterations;
}

EmFitResult EmFitter::fit(const WeightedSample* samples, size_t count) {
  EmFitResult result;
  if (!prepare(samples, count, result)) return result;
  Run best;
  if (!runK(1, best)) {
    result.reason = "single-component fit is not finite";
    return result;
  }
  double best_c = criterion(best);
  for (int k = 2; k <= options_.max_components; ++k) {
    // Too little evidence for k components of min_samples_per_component each: not eligible.
    if (n_eff_ < k * options_.min_samples_per_component) break;
    Run run;
    if (!runK(k, run)) continue;
    bool eligible = true;
    for (int j = 0; j < k; ++j) {
      eligible = eligible && run.pi[j] >= options_.min_component_weight &&
                 run.pi[j] * n_eff_ >= options_.min_samples_per_component;
    }
    if (!eligible) continue;
    const double c = criterion(run);
    if (std::isfinite(c) && c < best_c) {
      best_c = c;
      best = run;
    }
  }
  fillResult(best, result);
  for (int j = 0; j < result.mixture.size(); ++j) {
    const GaussianComponent& c = result.mixture.component(j);
    if (!std::isfinite(c.mean_m) || !(c.sigma_m > 0.f) || !std::isfinite(c.sigma_m) ||
        !(c.weight > 0.f)) {
      result.mixture.clear();
      result.reason = "fit is not finite";
    }
  }
  return result;
}

EmFitResult EmFitter::fitFixed(const WeightedSample* samples, size_t count, int components) {
  EmFitResult result;
  if (!prepare(samples, count, result)) return result;
  Run best;
  for (int k = std::clamp(components, 1, options_.max_components); k >= 1; --k) {
    if (runK(k, best)) {
      fillResult(best, result);
      return result;
    }
  }
  result.reason = "no finite fit";
  return result;
}

}  // namespace gmm_localization
