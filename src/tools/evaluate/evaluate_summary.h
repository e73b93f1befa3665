#pragma once
// The numbers of an evaluation (Table I, Fig. 8, match rate and latency, obstacles) computed
// from its rows, and their JSON and markdown renderings.

#include <cmath>
#include <string>

#include "evaluate/evaluate_integrity.h"
#include "evaluate/evaluate_results.h"

namespace gmm_localization {
namespace eval {

/// Reported EKF sigma [m] up to which a sample counts as localized.
constexpr double kLocalizedSigmaM = 1.0;

struct Quantiles {
  size_t count = 0;
  double p50 = NAN, p95 = NAN, max = NAN, mean = NAN;
};
Quantiles quantilesOf(const std::vector<double>& v);

struct Summary {
  ErrorSummary ekf;  ///< EKF output against ground truth (Table I)
  /// The same over the samples where the filter claims to be localized (reported sigma x and
  /// y <= kLocalizedSigmaM), e.g. without a start-up transient published with a 12 m sigma.
  ErrorSummary ekf_localized;
  size_t ekf_unlocalized = 0;  ///< samples left out of ekf_localized
  ErrorSummary raw;            ///< accepted scan matches against ground truth
  /// With --map-poses (evaluate_map_frame.h), over the rows where the map holds something:
  /// the EKF and the raw matches against the truth in the map's frame (the localization's
  /// own error), and the map's own error at the EKF samples' truth.
  ErrorSummary ekf_in_map, raw_in_map, map_error;
  size_t scans = 0;           ///< scans in the evaluated span (processed + dropped)
  size_t processed = 0;       ///< scans the matcher worked on
  size_t accepted = 0;        ///< accepted (published) matches
  size_t fused = 0;           ///< accepted matches the EKF fused
  double match_rate_hz = 0;   ///< accepted / duration
  double accepted_share = 0;  ///< accepted / scans
  Quantiles latency_s;        ///< result available - scan stamp, accepted matches
  Quantiles processing_ms;    ///< measured matcher time per processed scan
  // Fig. 8
  size_t offset_trials = 0;
  double offset_success = NAN;   ///< share within 0.5 m
  double offset_accepted = NAN;  ///< share accepted by the matcher's rules
  Quantiles offset_error_m;
  Quantiles offset_search_ms;
  double offset_mean_fraction = NAN;  ///< evaluations / exhaustive poses
  // Integrity (evaluate_integrity.h)
  IntegritySummary integrity_matches;  ///< accepted drive matches
  IntegritySummary integrity_offsets;  ///< Fig. 8 registrations
  // Obstacles
  double obstacle_precision = NAN, obstacle_recall = NAN;
};

Summary summarizeResults(const EvaluationResults& results);
/// Why there is nothing to score: neither an EKF estimate nor an accepted match met a
/// ground-truth pose (an empty bag, a wrong topic, a run that never localized). Empty when
/// there is something; then an empty series alone is reported as none ("-", null), never 0 cm.
std::string noDataReason(const EvaluationResults& results, const Summary& summary);
std::string summaryJson(const EvaluationResults& results, const Summary& summary);
std::string summaryMarkdown(const EvaluationResults& results, const Summary& summary);

}  // namespace eval
}  // namespace gmm_localization
