#pragma once
// Integrity of the matches (docs/integrity.md): how often a match is certified (availability),
// whether a certified match was ever wrong (hazardously misleading information: its error
// beyond its protection level, or beyond the alert limit), and the score deficit of the true
// pose that calibrates the certificate's margin. Computed for the drive's matches and for the
// Fig. 8 offset registrations.

#include <string>
#include <vector>

#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {
namespace eval {

/// Lane keeping on local streets: the alert limit of the integrity literature [m].
constexpr double kAlertLimitM = 0.29;

IntegrityFields integrityOf(const MatchResult& result);

struct IntegritySummary {
  size_t registrations = 0;  ///< with a result and a ground truth
  size_t certified = 0;
  double availability = NAN;  ///< certified / registrations
  /// Certified while the planar error exceeds the protection level / the alert limit.
  size_t misleading_beyond_protection = 0;
  size_t misleading_beyond_alert = 0;
  /// Uncertified with an error beyond the alert limit (flagged correctly).
  size_t flagged_beyond_alert = 0;
  std::vector<double> protection_xy_m;  ///< of the certified ones
  std::vector<double> truth_deficit;    ///< per point, where the truth was in the window
  size_t budget_exhausted = 0;          ///< uncertified because the proof ran out of budget
  std::vector<double> certificate_ms;   ///< time of each certificate
};

/// One registration: its planar error [m] against the truth and its integrity fields.
void addToIntegrity(const IntegrityFields& f, double error_m, IntegritySummary& s);
void finishIntegrity(IntegritySummary& s);

std::string integrityJson(const IntegritySummary& s);
/// A markdown paragraph; `what` names the registrations ("drive matches", "Fig. 8 offsets").
std::string integrityMarkdown(const IntegritySummary& s, const std::string& what);

}  // namespace eval
}  // namespace gmm_localization
