#pragma once
// Number formatting shared by the evaluate reports (evaluate_summary.cpp, evaluate_integrity.cpp):
// JSON numbers and fixed-point table cells, with a marker in place of a non-finite value.

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace gmm_localization {
namespace eval {

/// v with `precision` significant digits, for JSON; "null" when v is not finite.
inline std::string num(double v, int precision = 4) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

/// v with `digits` digits after the point, for tables; "-" when v is not finite.
inline std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

}  // namespace eval
}  // namespace gmm_localization
