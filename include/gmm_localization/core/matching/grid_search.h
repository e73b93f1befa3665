#pragma once
// Searches over the discretised x, y, heading space of a SearchProblem:
//  - exhaustiveSearch: paper Algorithm 2, the reference;
//  - branchAndBoundSearch: paper Algorithm 3, best-first over the multiresolution layers.
// Both maximise the base-layer score (the sum of quantized rasterized log-likelihoods, Eq. 1)
// and break ties identically: the smallest (heading index, ty, tx). Branch-and-bound therefore
// returns exactly the exhaustive optimum: each layer is an upper bound of the layer below over
// the node's block, and nodes are popped by (bound desc, first-leaf key asc).

#include <cstdint>
#include <vector>

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/matching/search_problem.h"

namespace gmm_localization {

struct SearchStats {
  int64_t evaluations = 0;                     ///< node scores computed, all layers
  std::vector<int64_t> evaluations_per_layer;  ///< index = layer
  int64_t exhaustive_poses = 0;                ///< poses Algorithm 2 scores for this window
  int64_t queue_peak = 0;                      ///< largest priority queue size
  int top_layer = 0;
  /// evaluations / exhaustive_poses
  double fraction() const {
    return exhaustive_poses > 0 ? static_cast<double>(evaluations) / exhaustive_poses : 0.0;
  }
};

struct SearchOutcome {
  int heading_index = 0;
  int tx = 0;
  int ty = 0;
  Pose6 pose;
  int64_t score = 0;            ///< quantized base-layer score
  double log_likelihood = 0.0;  ///< score converted to nats (Eq. 1 with the floor)
  SearchStats stats;
  /// Branch-and-bound only: the coarsest layer's node scores, index (j * ny + by) * nx + bx for
  /// heading j and block (bx, by) of stride 2^top_layer (nx, ny blocks per axis), so that the
  /// certificate (match_certificate.h) need not score that layer again. Empty otherwise.
  std::vector<int64_t> top_scores;
  /// Branch-and-bound only: the children's scores of every node it branched, sorted by key,
  /// so that the certificate need not score them again (childScores()). Empty otherwise.
  struct Branched {
    uint64_t key;       ///< branchKey(heading, layer of the children, tx, ty)
    int64_t scores[4];  ///< the four children's scores, as SearchProblem::scoreQuad gives them
  };
  std::vector<Branched> branched;
  /// The key of a branched node: its heading, its children's layer and its first translation,
  /// 16 bits each (a valid window is at most 8,193 cells and 4,097 headings wide:
  /// SearchWindow::validate).
  static uint64_t branchKey(int heading_index, int child_layer, int tx, int ty) {
    return (static_cast<uint64_t>(static_cast<uint16_t>(heading_index)) << 48) |
           (static_cast<uint64_t>(static_cast<uint16_t>(child_layer)) << 32) |
           (static_cast<uint64_t>(static_cast<uint16_t>(ty)) << 16) |
           static_cast<uint64_t>(static_cast<uint16_t>(tx));
  }
  /// The children's scores of the node (heading, child_layer, tx, ty) when the search branched
  /// it, else null.
  const int64_t* childScores(int heading_index, int child_layer, int tx, int ty) const;

  /// Global (heading-interval) search only, when complete: the bound of every node it scored,
  /// sorted by key, so that the global certificate need not compute them again
  /// (intervalBound()). Empty otherwise.
  struct IntervalBound {
    uint64_t key;  ///< intervalKey(j0, heading_level, layer, tx, ty)
    int64_t bound;
  };
  std::vector<IntervalBound> interval_bounds;
  /// The key of an interval node (16 bits for j0, tx, ty and 8 for the levels: see branchKey).
  static uint64_t intervalKey(int j0, int heading_level, int layer, int tx, int ty) {
    return (static_cast<uint64_t>(static_cast<uint16_t>(j0)) << 48) |
           (static_cast<uint64_t>(static_cast<uint8_t>(heading_level)) << 40) |
           (static_cast<uint64_t>(static_cast<uint8_t>(layer)) << 32) |
           (static_cast<uint64_t>(static_cast<uint16_t>(ty)) << 16) |
           static_cast<uint64_t>(static_cast<uint16_t>(tx));
  }
  /// The bound the search computed for that node, else null.
  const int64_t* intervalBound(int j0, int heading_level, int layer, int tx, int ty) const;

  /// Frees top_scores, branched and interval_bounds (once the certificate is proved).
  void dropCertificateMemos() {
    top_scores = {};
    branched = {};
    interval_bounds = {};
  }
};

/// One node the branch-and-bound scored (for the paper's Fig. 9 traversal picture).
struct TraversalNode {
  int16_t layer;
  int16_t heading_index;
  int16_t tx;
  int16_t ty;
  int64_t bound;
};

struct BranchAndBoundOptions {
  /// Score the prior (window centre) first and never queue nodes whose bound is below it:
  /// the optimum's ancestors all bound at least the prior's score, so nothing is lost.
  bool prior_as_incumbent = true;
};

SearchOutcome exhaustiveSearch(const SearchProblem& problem);

/// Paper Algorithm 3. `traversal`, when given, receives every node scored (one pass, no
/// threads). With `pool`, the top layer's headings are scored in parallel and the best-first
/// branching runs one pass per thread over an interleaved share of the headings, the passes
/// sharing the best leaf score found for pruning: the optimum (heading, tx, ty, score) is the
/// same as on one thread, bit for bit; the statistics (evaluations, queue peak) are the sums and
/// maxima of the passes and may differ from one run to the next.
SearchOutcome branchAndBoundSearch(const SearchProblem& problem,
                                   const BranchAndBoundOptions& options = {},
                                   std::vector<TraversalNode>* traversal = nullptr,
                                   TaskPool* pool = nullptr);

}  // namespace gmm_localization
