#pragma once
// Private to EmFitter: one EM run's state and helpers shared by em_fitter.cpp (model selection)
// and em_fitter_run.cpp (seeding and the EM iterations).

#include <array>
#include <limits>
#include <utility>

#include "gmm_localization/core/mapping/em_fitter.h"

namespace gmm_localization {
namespace em_detail {

/// Insertion sort of the first k entries (k <= 3); std::sort on a std::array prefix trips GCC
/// 12's -Warray-bounds.
template <typename T, typename Less>
void sortPrefix(std::array<T, kMaxMixtureComponents>& a, int k, Less less) {
  for (int i = 1; i < k; ++i) {
    for (int j = i; j > 0 && less(a[j], a[j - 1]); --j) std::swap(a[j], a[j - 1]);
  }
}

}  // namespace em_detail

/// One EM run: K components with parameters over the shifted, weight-normalised samples.
struct EmFitter::Run {
  int k = 0;
  std::array<double, kMaxMixtureComponents> pi{}, mu{}, var{};
  double ll = -std::numeric_limits<double>::infinity();  // sum_i w_i log p(z_i), sum w = 1
  double entropy = 0.0;                                  // sum_i w_i H(r_i)
  int iterations = 0;
  bool valid = false;
};

}  // namespace gmm_localization
