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
// frame) rotated by yaw_j instead of yaw_jm moves by d = R(a) q - q with |a| <= delta. Its
// length is 2 |q| sin(|a| / 2) <= |q| delta, and per axis |d_x| <= |q_x| (1 - cos delta) +
// |q_y| sin delta (|d_y| likewise with x and y exchanged; for delta beyond pi / 2 the sine's
// bound is 1, beyond pi the cosine's is 2). In cells, SearchProblem's cell of q at heading jm
// lies within one cell of q / res per axis around the prior's cell, so |q_x| / res <= ax =
// |dx| + 1 and |q_y| / res <= ay = |dy| + 1 with (dx, dy) that cell's offset from the prior's
// cell; the point's reach per axis is the smaller of the two bounds, r_x = min(hypot(ax, ay)
// delta, ax (1 - cos delta) + ay sin delta) and r_y likewise. Since |floor(a) - floor(b)| <=
// ceil(|a - b|), the point's cell at heading j is within m_x = ceil(r_x) cells in x (m_y in y)
// of its cell at jm; its z bin does not depend on heading (z, roll and pitch stay at the
// prior's). Over the node's translations [tx, tx + 2^L) the point therefore reads only base
// cells of the rectangle S = [gx + tx - m_x, gx + tx + 2^L + m_x) x [gy + ty - m_y, ...) at its
// z bin, and the largest base value over S bounds its contribution to every leaf of the node.
// Layer k at a cell is the max over the 2^k block starting there (a sliding window, not a
// tiling) and over a group of z bins containing the point's (map_chunk.h), so blocks of layer k
// placed at S's first cell, every 2^k cells, and the last one ending at S's far edge, cover S
// and their values bound that largest value; k is the finest layer whose cover needs at most
// max_reads_per_point blocks. A block whose starting chunk is not loaded is split at chunk
// borders: each piece is bounded by the layer value at its own first cell, or contributes
// nothing when its chunk is absent too, as the leaves there read the floor (0) as well. Summing
// point bounds times their merge counts bounds the node's leaves. At H = 0 and L = 0 the bound
// is the leaf's exact score, so best-first branching pops the exhaustive optimum, ties included
// (smallest heading index, then ty, then tx), exactly as branchAndBoundSearch does.
//
// Several queues. The roots are dealt to a fixed number of best-first queues that share the
// best leaf score proven so far (the incumbent, at first the prior's). A queue drops nodes whose
// bound is below the incumbent and stops when its best one is, or when it pops a leaf. A node
// holding an optimal leaf is never below the incumbent, so the queue holding the exhaustive
// optimum (the smallest key among the best scores) pops it, or an equal-score leaf of smaller
// key, which it cannot hold; the best leaf over the queues, smallest key among equal scores, is
// therefore the exhaustive optimum, on any number of threads and in any timing.
//
// A score floor. With min_score_per_point above the map's floor, the shared incumbent starts
// at the larger of the prior's score and that floor times the scan's points (in score units,
// rounded up). When the optimum reaches the floor the incumbent never exceeds it, so the argument
// above holds unchanged: the same optimum, ties included, with fewer nodes queued. When it does
// not, no leaf reaches the incumbent, the queues run dry without popping one, and the outcome
// says `below_floor`: proved, not guessed, that no pose of the window scores the floor (a window
// that does not hold the vehicle, which without the floor would be searched to its optimum or
// its budget).
//
// Verified against exhaustiveSearch on small randomized cases, and the bound against the max over
// its leaves, in test/unit/matching/global_search_test.cpp.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

#include "gmm_localization/core/common/task_pool.h"
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
  /// with `complete` false (no optimum proven). A 100 m x 100 m x 360 deg search of the demo
  /// town took 11k-107k node scores of 200 points (docs/benchmarks.md); 200000 of them, a few
  /// seconds on one core.
  int64_t max_evaluations = 200000;
  /// Score floor [nats per search point]: a window whose optimum scores below it is reported
  /// `below_floor` as soon as that is proved, instead of being searched to its optimum or its
  /// budget. At or below the map's ll_floor (-6 by default; -inf too): off. -4.5: the search
  /// optima of right matches scored -1.1 to -3.8 per point in the benchmarks (simulated clear,
  /// simulated snow on an aged map, real KITTI, each real keyframe against a map of the others),
  /// the complete searches of windows without the vehicle -5.6 to -5.8 (docs/benchmarks.md). The
  /// height likelihood only: off for a problem of two channels (the fused method) and in
  /// reflectivityRegistrationOptions.
  double min_score_per_point = -4.5;
  /// Search points of a wide-heading search (Registration thins the filtered scan's search
  /// points evenly to this many; 0: all). The optimum is exact for the points searched; the
  /// refinement still uses every voxel. The node count hardly depends on it, the time per node
  /// is proportional: 200 found all 10 of the benchmark's 100 m searches (benchmarks.md).
  size_t max_points = 200;
  /// Layer reads per point and node at most: the point's square is covered by the finest
  /// layer's blocks that need no more reads than this (1: one block of the next power of two,
  /// up to 4x the square's area; 4: within the square).
  int max_reads_per_point = 4;
  /// Best-first queues the roots are dealt to (root i to queue i % queues), sharing the best
  /// leaf proven so far; on a pool they run in parallel. 0: one per thread of the pool (one
  /// without). The optimum does not depend on it; the work does: queues run in turn without a
  /// pool, and a queue run first without the others' incumbent expands more than one queue.
  int queues = 0;
  /// After the global optimum (on max_points points), Registration searches this window
  /// around it on all the scan's points (the tracking search) and refines from there: the
  /// published pose, its covariance and its local certificate come from that search [m], [rad].
  double confirm_half_xy_m = 2.0;
  double confirm_half_heading_rad = 0.0524;  ///< 3 deg
  /// Threads of the global search and of its certificate, the caller's included (0: one per
  /// hardware thread): Registration runs them on a pool of their own when this differs from
  /// RegistrationOptions::threads. The queues share little (the best leaf), so a preempted
  /// worker delays its own queue only; a lost matcher has nothing else to do meanwhile.
  int threads = 1;

  std::string validate() const;
};

struct GlobalSearchOutcome {
  SearchOutcome best;      ///< the optimum (when complete) with the search statistics
  bool complete = true;    ///< false when max_evaluations stopped the search first
  bool cancelled = false;  ///< ... or when the caller's cancel flag did (complete false too)
  /// Proved that no pose of the window scores min_score_per_point (complete false, the prior
  /// reported as in a budget stop: there is no optimum worth the name here).
  bool below_floor = false;
  int64_t heading_splits = 0;
  int64_t translation_splits = 0;
  int64_t point_lookups = 0;  ///< table reads of the interval bounds
};

/// Exact global branch-and-bound over `problem`'s whole window (all its headings).
/// `pool`: the queues in parallel (the same optimum on any number of threads; the counts in
/// the statistics may differ, as a queue stops once another proved a better leaf).
/// `cancel`: when set (by another thread) the search stops at its next node score as at its
/// budget (`complete` and `cancelled`): the answer is no longer wanted (a newer pose came).
GlobalSearchOutcome globalBranchAndBound(const SearchProblem& problem,
                                         const GlobalSearchOptions& options = {},
                                         TaskPool* pool = nullptr,
                                         const std::atomic<bool>* cancel = nullptr);

/// The admissible bound of the node of headings [j0, j0 + 2^heading_level) (cut at the
/// window's last heading), translations [tx, tx + 2^layer) x [ty, ty + 2^layer), as argued
/// above; the leaf's exact score when heading_level = layer = 0. `lookups`, when given, is
/// increased by the table reads made. Exposed for the property test.
int64_t headingIntervalBound(const SearchProblem& problem, int j0, int heading_level, int layer,
                             int tx, int ty, int64_t* lookups = nullptr,
                             int max_reads_per_point = 4);

}  // namespace gmm_localization
