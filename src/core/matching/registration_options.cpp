// RegistrationOptions::validate and the names of the registration's failure kinds.

#include <string>

#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {

std::string RegistrationOptions::validate() const {
  std::string e = filter.validate();
  if (!e.empty()) return "filter: " + e;
  if (!(heading_step_rad > 0.0 && heading_step_rad < 0.2)) {
    return "heading_step_rad=" + std::to_string(heading_step_rad) + " must be in (0, 0.2)";
  }
  if (!(z_search_m >= 0.0 && z_search_m <= 20.0)) {
    return "z_search_m=" + std::to_string(z_search_m) + " must be in [0, 20]";
  }
  if (refine_max_points < 10) return "refine_max_points must be >= 10";
  e = hill_climb.validate();
  if (!e.empty()) return "hill_climb: " + e;
  e = covariance.validate();
  if (!e.empty()) return "covariance: " + e;
  e = certificate.validate();
  if (!e.empty()) return "certificate: " + e;
  if (interval_search_min_headings < 1) return "interval_search_min_headings must be >= 1";
  e = global.validate();
  if (!e.empty()) return "global: " + e;
  if (!(min_map_coverage >= 0.0 && min_map_coverage <= 1.0)) {
    return "min_map_coverage must be in [0, 1]";
  }
  if (threads < 0 || threads > TaskPool::kMaxThreads) {
    return "threads=" + std::to_string(threads) + " must be in [0, " +
           std::to_string(TaskPool::kMaxThreads) + "] (0: one per hardware thread)";
  }
  return {};
}

const char* registrationErrorName(RegistrationError kind) {
  switch (kind) {
    case RegistrationError::kNone:
      return "none";
    case RegistrationError::kInvalidOptions:
      return "invalid_options";
    case RegistrationError::kInvalidPrior:
      return "invalid_prior";
    case RegistrationError::kNoPoints:
      return "no_points";
    case RegistrationError::kInvalidWindow:
      return "invalid_window";
    case RegistrationError::kOffMap:
      return "off_map";
    case RegistrationError::kLowCoverage:
      return "low_coverage";
    case RegistrationError::kNumerical:
      return "numerical";
    case RegistrationError::kSearchBudget:
      return "search_budget";
    case RegistrationError::kCancelled:
      return "cancelled";
    case RegistrationError::kBelowFloor:
      return "below_floor";
  }
  return "unknown";
}

}  // namespace gmm_localization
