#pragma once
// A certificate for a search optimum: what the exact search can prove about the rest of its
// window after it has found the best pose.
//
// Scores are the base-layer scores of the search (SearchProblem::score at layer 0, the sum of
// quantized rasterized log-likelihoods); s* is the optimum's. Two quantities are proved, by a
// second branch-and-bound over the same layers (every layer bounds the layer below over its
// block, so a node whose bound is below a threshold holds no pose at or above it):
//
//  - separation: s* minus the best score of any pose "elsewhere", i.e. farther than
//    exclusion_radius_m in x, y or farther than exclusion_heading_rad in heading from the
//    optimum, in nats per scan point. Exact when it is below `separation_depth_per_point`;
//    otherwise the certificate proves only that it is at least that depth (separation_exact is
//    false and separation holds the depth).
//  - protection level: the largest distance from the optimum (x, y [m]; heading [rad]) of any
//    pose whose score is within `margin_per_point` of s* (the "plausible set"). The margin is
//    the score spread that sensor noise and map error give the true pose: on the simulator's
//    drives the true pose's score falls short of the optimum by at most the margin (calibrated
//    by `evaluate`, docs/integrity.md). If the true pose is in the window, it is then inside
//    the protection level around the optimum (up to the calibration's coverage).
//
// The match is certified when the plausible set lies inside the exclusion zone (protection
// levels within the exclusion radius and heading), no plausible pose lies on the window's
// border (the set might continue outside the window, where nothing is proved), and the work
// stayed within `max_evaluations`. A certified match is unambiguous inside its window; it does
// not prove that the window holds the truth (a prior far off can put the truth outside it: the
// matcher's other checks and the global search cover that).
//
// Cost: the certificate scores the coarsest layer once more (or reuses the branch-and-bound's
// scores of it, SearchOutcome::top_scores) and then only nodes whose bound
// reaches s* minus the larger of the margin and the separation depth, so a sharp optimum costs
// a small fraction of the search and a flat one (a corridor, a repeating facade) runs into the
// budget and is reported uncertified ("budget").

#include <algorithm>
#include <cstdint>
#include <string>

#include "gmm_localization/core/matching/grid_search.h"

namespace gmm_localization {

struct CertificateOptions {
  bool enabled = true;
  double exclusion_radius_m = 0.5;       ///< [m] "elsewhere" starts farther than this in x, y
  double exclusion_heading_rad = 0.035;  ///< [rad] (2 deg) or farther than this in heading
  /// Score deficit of a plausible pose [nats per scan point] (see the header comment).
  double margin_per_point = 0.05;
  /// Separation is computed exactly up to this deficit [nats per scan point]; must be at
  /// least the margin.
  double separation_depth_per_point = 0.1;
  /// Node scores the certificate may compute (all layers); beyond it: not certified.
  int64_t max_evaluations = 3000;
  /// Windows at least this wide (half extent in x or y [m]) get wide_max_evaluations instead:
  /// the wide window after an initial pose or a relocalization (12.5 m), not the tracking window
  /// (a few metres). Such a search runs once per relocalization, and its certificate decides
  /// whether the jump is taken (the matcher's require_certificate_wide); a proof stopped at the
  /// budget sends the localization into the global search, seconds later. The fused method's two
  /// channels bound less sharply: in snow its first wide proof needed about 10x the tracking
  /// budget (335 ms with 30000; docs/integrity.md).
  double wide_min_half_xy_m = 5.0;
  int64_t wide_max_evaluations = 30000;
  /// The same for the certificate of a global search (global_certificate.h), whose nodes span
  /// heading intervals over a window thousands of times larger.
  int64_t global_max_evaluations = 200000;

  std::string validate() const;
  /// The node budget of a window with these half extents [m].
  int64_t budgetFor(double half_x_m, double half_y_m) const {
    return std::max(half_x_m, half_y_m) >= wide_min_half_xy_m ? wide_max_evaluations
                                                              : max_evaluations;
  }
};

/// Why a match is not certified ("" when it is).
enum class CertificateFailure {
  kNone,
  kDisabled,    ///< certificates switched off
  kAmbiguous,   ///< a plausible pose lies outside the exclusion zone
  kWindowEdge,  ///< a plausible pose lies on the window's border
  kBudget,      ///< max_evaluations reached before the proof completed
};
const char* certificateFailureName(CertificateFailure failure);  ///< "", "ambiguous", ...

struct MatchCertificate {
  bool certified = false;
  CertificateFailure failure = CertificateFailure::kDisabled;
  /// s* minus the best score elsewhere [nats per scan point]; a lower bound (the depth) when
  /// separation_exact is false.
  double separation_per_point = 0.0;
  bool separation_exact = false;
  /// Largest distance from the optimum of a plausible pose: x-y [m] and heading [rad].
  /// Meaningful only when certified (otherwise at least the values found before stopping).
  double protection_xy_m = 0.0;
  double protection_heading_rad = 0.0;
  int64_t evaluations = 0;  ///< node scores computed
};

/// Certifies `optimum`, the exact optimum of `problem` (exhaustiveSearch/branchAndBoundSearch).
/// `pool`: the next node's children are scored ahead, beside the current node's, and used when
/// that node is popped next: the same certificate and evaluation count as without a pool.
MatchCertificate certifyOptimum(const SearchProblem& problem, const SearchOutcome& optimum,
                                const CertificateOptions& options, TaskPool* pool = nullptr);

}  // namespace gmm_localization
