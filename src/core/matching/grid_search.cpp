#include "gmm_localization/core/matching/grid_search.h"

#include <algorithm>
#include <atomic>
#include <queue>
#include <vector>

#include "search_node.h"

namespace gmm_localization {
namespace search_detail {

SearchOutcome makeOutcome(const SearchProblem& problem, int j, int tx, int ty, int64_t score,
                          SearchStats stats) {
  SearchOutcome out;
  out.heading_index = j;
  out.tx = tx;
  out.ty = ty;
  out.pose = problem.pose(j, tx, ty);
  out.score = score;
  out.log_likelihood =
      ScoreQuantizer(problem.map().options()).sumToLogLikelihood(score, problem.scanPoints());
  out.stats = std::move(stats);
  return out;
}

}  // namespace search_detail

namespace {
/// The record of `key` in `sorted` (ordered by key), or null.
template <typename Record>
const Record* findByKey(const std::vector<Record>& sorted, uint64_t key) {
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), key,
                                   [](const Record& r, uint64_t k) { return r.key < k; });
  return it != sorted.end() && it->key == key ? &*it : nullptr;
}
}  // namespace

const int64_t* SearchOutcome::childScores(int heading_index, int child_layer, int tx,
                                          int ty) const {
  const Branched* b = findByKey(branched, branchKey(heading_index, child_layer, tx, ty));
  return b != nullptr ? b->scores : nullptr;
}

const int64_t* SearchOutcome::intervalBound(int j0, int heading_level, int layer, int tx,
                                            int ty) const {
  const IntervalBound* b =
      findByKey(interval_bounds, intervalKey(j0, heading_level, layer, tx, ty));
  return b != nullptr ? &b->bound : nullptr;
}

namespace {

using search_detail::keyLess;
using search_detail::Lower;
using search_detail::makeOutcome;
using search_detail::Node;

}  // namespace

SearchOutcome exhaustiveSearch(const SearchProblem& problem) {
  const SearchWindow& w = problem.window();
  SearchStats stats;
  stats.exhaustive_poses = w.poses();
  stats.evaluations = w.poses();
  stats.evaluations_per_layer = {w.poses()};
  int best_j = 0, best_tx = 0, best_ty = 0;
  int64_t best = -1;
  std::vector<int64_t> scores;
  for (int j = 0; j < w.sizeH(); ++j) {
    problem.scoreBlock(j, 0, 0, w.sizeX(), w.sizeY(), scores);
    for (int ty = 0; ty < w.sizeY(); ++ty) {
      for (int tx = 0; tx < w.sizeX(); ++tx) {
        const int64_t s = scores[static_cast<size_t>(ty) * w.sizeX() + tx];
        if (s > best) {  // strict: the first in (j, ty, tx) order keeps a tie
          best = s;
          best_j = j;
          best_tx = tx;
          best_ty = ty;
        }
      }
    }
  }
  return makeOutcome(problem, best_j, best_tx, best_ty, best, std::move(stats));
}

namespace {

/// The best leaf one best-first pass found: its score and key (heading, ty, tx).
struct Leaf {
  bool found = false;
  int64_t score = -1;
  int j = 0, tx = 0, ty = 0;
};

/// Counts (and, when `traversal` is given, records) the nodes one pass scores; `branched`
/// receives the children's scores of each node the pass branched.
struct NodeLog {
  SearchStats* stats;
  std::vector<TraversalNode>* traversal;
  std::vector<SearchOutcome::Branched>* branched;
  void add(int j, int layer, int tx, int ty, int64_t s) {
    ++stats->evaluations;
    ++stats->evaluations_per_layer[layer];
    if (traversal != nullptr) {
      traversal->push_back({static_cast<int16_t>(layer), static_cast<int16_t>(j),
                            static_cast<int16_t>(tx), static_cast<int16_t>(ty), s});
    }
  }
};

/// Lines 19-35 of Algorithm 3 over the top-layer nodes of the headings j with j % groups ==
/// group: best-first until a base-layer node pops (the best leaf of those headings) or no node
/// can reach `shared_best` any more (another pass holds a better leaf). Nodes bounding strictly
/// below `shared_best` are never queued; equal ones are (a tie may win on its key).
Leaf bestFirst(const SearchProblem& problem, const std::vector<int64_t>& all_top, int group,
               int groups, std::atomic<int64_t>& shared_best, NodeLog log) {
  const SearchWindow& w = problem.window();
  const int top = problem.topLayer();
  const int stride = 1 << top;
  const int nx = (w.sizeX() + stride - 1) / stride, ny = (w.sizeY() + stride - 1) / stride;
  std::priority_queue<Node, std::vector<Node>, Lower> queue;
  auto push = [&](const Node& n) {
    if (n.bound < shared_best.load(std::memory_order_relaxed)) return;
    queue.push(n);
    log.stats->queue_peak =
        std::max<int64_t>(log.stats->queue_peak, static_cast<int64_t>(queue.size()));
  };
  for (int j = group; j < w.sizeH(); j += groups) {
    const int64_t* top_scores = all_top.data() + static_cast<size_t>(j) * nx * ny;
    for (int by = 0; by < ny; ++by) {
      for (int bx = 0; bx < nx; ++bx) {
        const int64_t s = top_scores[static_cast<size_t>(by) * nx + bx];
        log.add(j, top, bx * stride, by * stride, s);
        push({s, j, by * stride, bx * stride, top});
      }
    }
  }
  while (!queue.empty()) {
    const Node n = queue.top();
    queue.pop();
    if (n.bound < shared_best.load(std::memory_order_relaxed)) break;  // nothing left can win
    if (n.layer == 0) {
      int64_t seen = shared_best.load(std::memory_order_relaxed);
      while (n.bound > seen && !shared_best.compare_exchange_weak(seen, n.bound)) {
      }
      return {true, n.bound, n.heading_index, n.tx, n.ty};
    }
    // Branch into the (up to) four children at the next finer layer, scored in one pass.
    const int child = n.layer - 1;
    const int h = 1 << child;
    SearchOutcome::Branched& b = log.branched->emplace_back();
    b.key = SearchOutcome::branchKey(n.heading_index, child, n.tx, n.ty);
    int64_t* scores = b.scores;
    problem.scoreQuad(n.heading_index, child, n.tx, n.ty, h, scores);
    for (int dy = 0; dy < 2; ++dy) {
      const int ty = n.ty + dy * h;
      if (ty >= w.sizeY()) break;
      for (int dx = 0; dx < 2; ++dx) {
        const int tx = n.tx + dx * h;
        if (tx >= w.sizeX()) break;
        log.add(n.heading_index, child, tx, ty, scores[dy * 2 + dx]);
        push({scores[dy * 2 + dx], n.heading_index, ty, tx, child});
      }
    }
  }
  return {};
}

}  // namespace

SearchOutcome branchAndBoundSearch(const SearchProblem& problem,
                                   const BranchAndBoundOptions& options,
                                   std::vector<TraversalNode>* traversal, TaskPool* pool) {
  const SearchWindow& w = problem.window();
  const int top = problem.topLayer();
  SearchStats stats;
  stats.exhaustive_poses = w.poses();
  stats.top_layer = top;
  stats.evaluations_per_layer.assign(top + 1, 0);

  int64_t incumbent = -1;
  if (options.prior_as_incumbent) {
    incumbent = problem.score(w.half_h, 0, w.half_x, w.half_y);
    NodeLog{&stats, traversal, nullptr}.add(w.half_h, 0, w.half_x, w.half_y, incumbent);
  }

  // Exhaustive over the coarsest layer (Algorithm 3, lines 5-17), four nodes per pass over the
  // points, the headings in parallel (each writes its own slice).
  const int stride = 1 << top;
  const int nx = (w.sizeX() + stride - 1) / stride, ny = (w.sizeY() + stride - 1) / stride;
  std::vector<int64_t> all_top(static_cast<size_t>(nx) * ny * w.sizeH());
  parallelFor(pool, w.sizeH(), [&](int j) {
    int64_t* top_scores = all_top.data() + static_cast<size_t>(j) * nx * ny;
    for (int by = 0; by < ny; by += 2) {
      for (int bx = 0; bx < nx; bx += 2) {
        int64_t quad[4];
        problem.scoreQuad(j, top, bx * stride, by * stride, stride, quad);
        for (int dy = 0; dy < 2 && by + dy < ny; ++dy) {
          for (int dx = 0; dx < 2 && bx + dx < nx; ++dx) {
            top_scores[static_cast<size_t>(by + dy) * nx + bx + dx] = quad[dy * 2 + dx];
          }
        }
      }
    }
  });

  // Best-first branching (lines 19-35): a popped base-layer node is the optimum. With a pool,
  // one pass per thread over an interleaved share of the headings, sharing the best leaf score
  // found so far for pruning; the best of the passes' leaves (score, then the smallest key) is
  // the same optimum a single pass over every heading pops. A traversal is recorded by one pass.
  const int groups = (pool == nullptr || traversal != nullptr)
                         ? 1
                         : std::min(pool->threads(), std::max(1, w.sizeH()));
  std::atomic<int64_t> shared_best{incumbent};
  std::vector<Leaf> leaves(static_cast<size_t>(groups));
  std::vector<SearchStats> group_stats(static_cast<size_t>(groups), stats);
  std::vector<std::vector<SearchOutcome::Branched>> group_branched(static_cast<size_t>(groups));
  for (SearchStats& g : group_stats) {
    g.evaluations = 0;
    g.evaluations_per_layer.assign(top + 1, 0);
  }
  auto pass = [&](int g) {
    leaves[static_cast<size_t>(g)] =
        bestFirst(problem, all_top, g, groups, shared_best,
                  {&group_stats[static_cast<size_t>(g)], groups == 1 ? traversal : nullptr,
                   &group_branched[static_cast<size_t>(g)]});
  };
  if (groups == 1) {
    pass(0);
  } else {
    pool->run(groups, pass);
  }
  Leaf best;
  for (size_t g = 0; g < leaves.size(); ++g) {
    const Leaf& l = leaves[g];
    const SearchStats& gs = group_stats[g];
    stats.evaluations += gs.evaluations;
    for (int layer = 0; layer <= top; ++layer) {
      stats.evaluations_per_layer[layer] += gs.evaluations_per_layer[layer];
    }
    stats.queue_peak = std::max(stats.queue_peak, gs.queue_peak);
    if (l.found &&
        (!best.found || l.score > best.score ||
         (l.score == best.score && keyLess(l.j, l.ty, l.tx, best.j, best.ty, best.tx)))) {
      best = l;
    }
  }
  if (!best.found) {
    // Unreachable while the bounds are admissible (the prior's own leaf always survives).
    return makeOutcome(problem, w.half_h, w.half_x, w.half_y, incumbent, std::move(stats));
  }
  SearchOutcome out = makeOutcome(problem, best.j, best.tx, best.ty, best.score, std::move(stats));
  out.top_scores = std::move(all_top);
  // The passes branch disjoint headings: their nodes' keys are distinct.
  for (std::vector<SearchOutcome::Branched>& g : group_branched) {
    out.branched.insert(out.branched.end(), g.begin(), g.end());
  }
  search_detail::sortByKey(out.branched);
  return out;
}

}  // namespace gmm_localization
