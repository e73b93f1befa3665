#pragma once
// Global localization by the same exact search: branch-and-bound over x, y AND heading
// intervals, for windows far larger than the tracking search's (100 m x 100 m x 360 deg).
//
// The tracking search (grid_search.h) scores every heading of its window at the coarsest layer;
// over 720 headings of a full turn that alone costs more than the rest of the search. Here a
// node is a block of 2^L x 2^L translations times an interval of 2^H consecutive headings, and
// its bound is admissible by the following argument.
//
// Admissibility of a heading-interval bound. Let the node's headings be j in [j0, j1], jm the
// middle one and delta = max(jm - j0, j1 - jm) * heading_step. A scan point q (levelled base
// frame) rotated by yaw_j instead of yaw_jm moves by |R(yaw_j) q - R(yaw_jm) q| =
// 2 |q| sin(|yaw_j - yaw_jm| / 2) <= |q| delta. In cells that is at most r delta with r >= |q| /
// res; SearchProblem's cell of q at heading jm lies within one cell of q / res per axis around
// the prior's cell, so r = hypot(|dx| + 1, |dy| + 1) with (dx, dy) that cell's offset from the
// prior's cell bounds |q| / res. Since |floor(a) - floor(b)| <= ceil(|a - b|), the point's cell
// at heading j is within m = ceil(r delta) cells per axis of its cell at jm; its z bin does not
// depend on heading (z, roll and pitch stay at the prior's). Over the node's translations
// [tx, tx + 2^L) the point therefore reads only base cells of the square
// S = [gx + tx - m, gx + tx + 2^L + m) x [same in y] at its z bin, and the largest base value
// over S bounds its contribution to every leaf of the node. That largest value is bounded by
// the values of layer k at the starts of blocks of 2^k cells tiling S (layer k at a cell is the
// max over the 2^k block starting there and over a group of z bins containing the point's,
// map_chunk.h). A block whose starting chunk is not loaded is split at chunk borders: each
// piece is bounded by the layer value at its own first cell, or contributes nothing when its
// chunk is absent too, as the leaves there read the floor (0) as well. Summing point bounds
// times their merge counts bounds the node's leaves. At H = 0 and L = 0 the bound is the leaf's
// exact score, so best-first branching pops the exhaustive optimum, ties included (smallest
// heading index, then ty, then tx), exactly as branchAndBoundSearch does.
//
// Verified against exhaustiveSearch on small randomized cases, and the bound against the max over
// its leaves, in test/unit/matching/global_search_test.cpp.

#include <cstddef>
#include <cstdint>
#include <string>

#include "gmm_localization/core/matching/grid_search.h"
#include "gmm_localization/core/matching/search_problem.h"

namespace gmm_localization {

struct GlobalSearchOptions {
  /// Root nodes span 2^root_heading_levels headings (5: 32 headings, 16 deg at the 0.5 deg step).
  int root_heading_levels = 5;
  /// Root translation blocks span 2^root_layer cells; -1: the problem's top layer. Layers above
  /// the map's coarsest are bounded by several lookups per point.
  int root_layer = -1;
  /// A node splits its heading interval, not its translations, while its typical point (this
  /// quantile of the scan's ranges) moves across the interval by at least this share of the
  /// node's translation block.
  double heading_split_share = 0.5;
  double typical_range_quantile = 0.5;
  /// Score the prior (window centre, middle heading) first and never queue nodes below it.
  bool prior_as_incumbent = true;
  /// Node scores at most; 0: unbounded. When reached the search stops and reports the prior
  /// with `complete` false (no optimum proven). 200000 node scores of 1000 points: tens of
  /// seconds on one core.
  int64_t max_evaluations = 200000;
  /// Search points of a wide-heading search (Registration thins the filtered scan's search
  /// points evenly to this many; 0: all). The optimum is exact for the points searched; the
  /// refinement still uses every voxel.
  size_t max_points = 1000;

  std::string validate() const;
};

struct GlobalSearchOutcome {
  SearchOutcome best;    ///< the optimum (when complete) with the search statistics
  bool complete = true;  ///< false when max_evaluations stopped the search first
  int64_t heading_splits = 0;
  int64_t translation_splits = 0;
  int64_t point_lookups = 0;  ///< table reads of the interval bounds
};

/// Exact global branch-and-bound over `problem`'s whole window (all its headings).
GlobalSearchOutcome globalBranchAndBound(const SearchProblem& problem,
                                         const GlobalSearchOptions& options = {});

/// The admissible bound of the node of headings [j0, j0 + 2^heading_level) (cut at the
/// window's last heading), translations [tx, tx + 2^layer) x [ty, ty + 2^layer), as argued
/// above; the leaf's exact score when heading_level = layer = 0. `lookups`, when given, is
/// increased by the table reads made. Exposed for the property test.
int64_t headingIntervalBound(const SearchProblem& problem, int j0, int heading_level, int layer,
                             int tx, int ty, int64_t* lookups = nullptr);

}  // namespace gmm_localization
