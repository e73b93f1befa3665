#include "gmm_localization/core/matching/grid_search.h"

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

SearchOutcome branchAndBoundSearch(const SearchProblem& problem,
                                   const BranchAndBoundOptions& options,
                                   std::vector<TraversalNode>* traversal) {
  const SearchWindow& w = problem.window();
  const int top = problem.topLayer();
  SearchStats stats;
  stats.exhaustive_poses = w.poses();
  stats.top_layer = top;
  stats.evaluations_per_layer.assign(top + 1, 0);

  auto record = [&](int j, int layer, int tx, int ty, int64_t s) {
    ++stats.evaluations;
    ++stats.evaluations_per_layer[layer];
    if (traversal != nullptr) {
      traversal->push_back({static_cast<int16_t>(layer), static_cast<int16_t>(j),
                            static_cast<int16_t>(tx), static_cast<int16_t>(ty), s});
    }
  };
  auto evaluate = [&](int j, int layer, int tx, int ty) {
    const int64_t s = problem.score(j, layer, tx, ty);
    record(j, layer, tx, ty, s);
    return s;
  };

  int64_t incumbent = -1;
  if (options.prior_as_incumbent) incumbent = evaluate(w.half_h, 0, w.half_x, w.half_y);

  std::priority_queue<Node, std::vector<Node>, Lower> queue;
  auto push = [&](const Node& n) {
    if (n.bound < incumbent) return;  // cannot contain a pose scoring at least the prior
    queue.push(n);
    stats.queue_peak = std::max<int64_t>(stats.queue_peak, static_cast<int64_t>(queue.size()));
  };

  // Exhaustive over the coarsest layer (Algorithm 3, lines 5-17), four nodes per pass over the
  // points, then queued in (heading, ty, tx) order.
  const int stride = 1 << top;
  const int nx = (w.sizeX() + stride - 1) / stride, ny = (w.sizeY() + stride - 1) / stride;
  std::vector<int64_t> all_top(static_cast<size_t>(nx) * ny * w.sizeH());
  for (int j = 0; j < w.sizeH(); ++j) {
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
    for (int by = 0; by < ny; ++by) {
      for (int bx = 0; bx < nx; ++bx) {
        const int64_t s = top_scores[static_cast<size_t>(by) * nx + bx];
        record(j, top, bx * stride, by * stride, s);
        push({s, j, by * stride, bx * stride, top});
      }
    }
  }
  // Best-first branching (lines 19-35): a popped base-layer node is the optimum.
  while (!queue.empty()) {
    const Node n = queue.top();
    queue.pop();
    if (n.layer == 0) {
      SearchOutcome out =
          makeOutcome(problem, n.heading_index, n.tx, n.ty, n.bound, std::move(stats));
      out.top_scores = std::move(all_top);
      return out;
    }
    // Branch into the (up to) four children at the next finer layer, scored in one pass.
    const int child = n.layer - 1;
    const int h = 1 << child;
    int64_t scores[4];
    problem.scoreQuad(n.heading_index, child, n.tx, n.ty, h, scores);
    for (int dy = 0; dy < 2; ++dy) {
      const int ty = n.ty + dy * h;
      if (ty >= w.sizeY()) break;
      for (int dx = 0; dx < 2; ++dx) {
        const int tx = n.tx + dx * h;
        if (tx >= w.sizeX()) break;
        record(n.heading_index, child, tx, ty, scores[dy * 2 + dx]);
        push({scores[dy * 2 + dx], n.heading_index, ty, tx, child});
      }
    }
  }
  // Unreachable while the bounds are admissible (the prior's own leaf always survives).
  return makeOutcome(problem, w.half_h, w.half_x, w.half_y, incumbent, std::move(stats));
}

}  // namespace gmm_localization
