#pragma once
// The `simulate` options that make the world imperfect the way a deployment is: a slightly
// wrong extrinsic calibration (--extrinsic-error*) and a town that changed since the mapping
// drive (--aging*). Kept apart from the main parser (simulate_options.cpp).

#include <string>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/simulation.h"

namespace gmm_localization {
namespace tools {

/// The option's value as a finite number, or a failure naming the option (every numeric
/// option of `simulate` is read by it).
Result<double> parseOptionNumber(const std::string& opt, const std::string& v);

/// Which of the options were given (a numeric override without its mode is refused).
struct ImperfectionFlags {
  std::string extrinsic_override;  ///< the last --extrinsic-error-* option given, if any
  std::string aging_override;      ///< the last --aging-* option given, if any
};

/// Applies option `name` with `value` to `config` if it is one of these options. Returns true
/// when it was (false: not one of these options), or a failure naming the option.
Result<bool> applyImperfectionOption(const std::string& name, const std::string& value,
                                     sim::SimulationConfig* config, ImperfectionFlags* flags);

/// Checks after parsing: overrides need their mode, aging needs a localization pass.
Status checkImperfectionOptions(const sim::SimulationConfig& config,
                                const ImperfectionFlags& flags);

}  // namespace tools
}  // namespace gmm_localization
