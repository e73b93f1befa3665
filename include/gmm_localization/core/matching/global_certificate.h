#pragma once
// The certificate (match_certificate.h) of a global search's optimum (global_search.h): the
// same two quantities, proved over the whole global window by a branch-and-bound over x, y and
// heading intervals with the global search's admissible bounds.
//
// With s* the optimum's score over the global problem's search points (GlobalSearchOptions::
// max_points of them), a node whose interval bound is below s* minus the margin holds no
// plausible pose: it is dropped (the separation is proved down to the margin, not to
// separation_depth_per_point: deeper, the proof costs several times more).
// The others are split (the global search's split rule) until a leaf, an exact base-layer
// score, decides: a plausible leaf outside the exclusion zone (farther than exclusion_radius_m
// in x, y or exclusion_heading_rad in heading from the optimum) is "ambiguous"; a plausible leaf
// on the border of the window's translations (or of its headings, when they do not close the
// full turn) is "window_edge"; running past global_max_evaluations node scores is "budget".
// Headings are compared around the circle when the window covers the full turn.
//
// The certificate is exact for the search points it scores, like the search: it proves that no
// pose of the window elsewhere scores within the margin of the optimum on those points. The
// pose published after a global search is refined on all points (Registration), whose own
// certificate covers the neighbourhood; the match is certified only when both are.

#include <atomic>

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/matching/global_search.h"
#include "gmm_localization/core/matching/match_certificate.h"

namespace gmm_localization {

/// Certifies `optimum`, the exact optimum of globalBranchAndBound(problem, search) (complete).
/// `search` supplies the roots, the split rule, the reads per point and the queues: the roots
/// are dealt to GlobalSearchOptions::queues best-first queues (0: one per thread of `pool`),
/// run in parallel on `pool`. The proof does not depend on the queues when it completes within
/// the budget (every node reaching the floor that can change it is split, in any order); the
/// evaluation count does. separation_per_point is a lower bound: the margin, or 0 when
/// ambiguous. `cancel` (optional): checked before each node; once set, every queue stops, the
/// certificate is not certified (failure kBudget: an unfinished proof) and `*cancelled` is set.
MatchCertificate certifyGlobalOptimum(const SearchProblem& problem, const SearchOutcome& optimum,
                                      const CertificateOptions& options,
                                      const GlobalSearchOptions& search, TaskPool* pool = nullptr,
                                      const std::atomic<bool>* cancel = nullptr,
                                      bool* cancelled = nullptr);

}  // namespace gmm_localization
