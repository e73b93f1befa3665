#pragma once
// Range checks shared by the options' validate() functions.

#include <cmath>
#include <sstream>
#include <string>

namespace gmm_localization {

/// Empty when lo <= value <= hi (value finite), else "<key> = <value> must be in [lo, hi]".
inline std::string rangeProblem(const char* key, double value, double lo, double hi) {
  if (std::isfinite(value) && value >= lo && value <= hi) return {};
  std::ostringstream s;
  s << key << " = " << value << " must be in [" << lo << ", " << hi << "]";
  return s.str();
}

}  // namespace gmm_localization
