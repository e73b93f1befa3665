#include "evaluate/evaluate_integrity.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "evaluate/evaluate_format.h"
#include "evaluate/evaluate_metrics.h"

namespace gmm_localization {
namespace eval {
namespace {

double quantileOr(const std::vector<double>& v, double q) {
  return v.empty() ? NAN : quantile(v, q);
}

double maxOr(const std::vector<double>& v) {
  return v.empty() ? NAN : *std::max_element(v.begin(), v.end());
}

}  // namespace

IntegrityFields integrityOf(const MatchResult& r) {
  IntegrityFields f;
  f.valid = true;
  f.certified = r.certificate.certified;
  f.failure = certificateFailureName(r.certificate.failure);
  f.protection_xy_m = r.protection_xy_m;
  f.protection_heading_rad = r.protection_heading_rad;
  f.separation_per_point = r.certificate.separation_per_point;
  f.truth_deficit_per_point = r.reference_deficit_per_point;
  return f;
}

void addToIntegrity(const IntegrityFields& f, double error_m, IntegritySummary& s) {
  if (!f.valid || !std::isfinite(error_m)) return;
  ++s.registrations;
  s.certificate_ms.push_back(f.certificate_ms);
  if (f.failure == "budget") ++s.budget_exhausted;
  if (std::isfinite(f.truth_deficit_per_point))
    s.truth_deficit.push_back(f.truth_deficit_per_point);
  if (f.certified) {
    ++s.certified;
    s.protection_xy_m.push_back(f.protection_xy_m);
    if (error_m > f.protection_xy_m) ++s.misleading_beyond_protection;
    if (error_m > kAlertLimitM) ++s.misleading_beyond_alert;
  } else if (error_m > kAlertLimitM) {
    ++s.flagged_beyond_alert;
  }
}

void finishIntegrity(IntegritySummary& s) {
  s.availability = s.registrations > 0 ? static_cast<double>(s.certified) / s.registrations : NAN;
}

std::string integrityJson(const IntegritySummary& s) {
  std::ostringstream o;
  o << "{\"registrations\": " << s.registrations << ", \"certified\": " << s.certified
    << ", \"availability\": " << num(s.availability)
    << ", \"misleading_beyond_protection\": " << s.misleading_beyond_protection
    << ", \"misleading_beyond_alert_limit\": " << s.misleading_beyond_alert
    << ", \"uncertified_beyond_alert_limit\": " << s.flagged_beyond_alert
    << ", \"alert_limit_m\": " << num(kAlertLimitM)
    << ", \"protection_xy_m_p50\": " << num(quantileOr(s.protection_xy_m, 0.5))
    << ", \"protection_xy_m_p95\": " << num(quantileOr(s.protection_xy_m, 0.95))
    << ", \"truth_deficit_count\": " << s.truth_deficit.size()
    << ", \"truth_deficit_p50\": " << num(quantileOr(s.truth_deficit, 0.5))
    << ", \"truth_deficit_p99\": " << num(quantileOr(s.truth_deficit, 0.99))
    << ", \"truth_deficit_max\": " << num(maxOr(s.truth_deficit))
    << ", \"budget_exhausted\": " << s.budget_exhausted
    << ", \"certificate_ms_p50\": " << num(quantileOr(s.certificate_ms, 0.5))
    << ", \"certificate_ms_p95\": " << num(quantileOr(s.certificate_ms, 0.95))
    << ", \"certificate_ms_max\": " << num(maxOr(s.certificate_ms)) << "}";
  return o.str();
}

std::string integrityMarkdown(const IntegritySummary& s, const std::string& what) {
  std::ostringstream o;
  o << "Integrity (" << what << "): ";
  if (s.registrations == 0) {
    o << "no registrations with ground truth.\n\n";
    return o.str();
  }
  o << s.certified << " of " << s.registrations << " certified (availability "
    << fixed(100.0 * s.availability, 1) << "%); hazardously misleading (certified, error beyond "
    << "the protection level / beyond the " << fixed(kAlertLimitM, 2)
    << " m alert limit): " << s.misleading_beyond_protection << " / " << s.misleading_beyond_alert
    << "; uncertified beyond the alert limit: " << s.flagged_beyond_alert
    << "; protection level median " << fixed(quantileOr(s.protection_xy_m, 0.5), 2) << " m, p95 "
    << fixed(quantileOr(s.protection_xy_m, 0.95), 2) << " m; the truth's score deficit "
    << "[nats per point] median " << fixed(quantileOr(s.truth_deficit, 0.5), 4) << ", p99 "
    << fixed(quantileOr(s.truth_deficit, 0.99), 4) << ", max " << fixed(maxOr(s.truth_deficit), 4)
    << " (" << s.truth_deficit.size() << " with the truth "
    << "in the window); " << s.budget_exhausted << " out of budget; certificate time median "
    << fixed(quantileOr(s.certificate_ms, 0.5), 1) << " ms, p95 "
    << fixed(quantileOr(s.certificate_ms, 0.95), 1) << " ms, max "
    << fixed(maxOr(s.certificate_ms), 1) << " ms.\n\n";
  return o.str();
}

}  // namespace eval
}  // namespace gmm_localization
