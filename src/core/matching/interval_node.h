#pragma once
// A node of the branch-and-bound over x, y AND heading intervals (global_search.h), shared by
// the global search and its certificate (global_certificate.cpp): the node, its heap order, the
// roots, and how a node splits into children. Private to the matching stage.

#include <cstdint>

#include "gmm_localization/core/matching/global_search.h"
#include "search_node.h"

namespace gmm_localization {
namespace search_detail {

/// Headings [j0, j0 + 2^heading_level), translations [tx, tx + 2^layer) per axis.
struct IntervalNode {
  int64_t bound;
  int32_t j0;
  int32_t ty;
  int32_t tx;
  int16_t layer;
  int16_t heading_level;

  bool leaf() const { return layer == 0 && heading_level == 0; }
};

/// Higher bound first; on equal bounds the smaller first-leaf key (j0, ty, tx) first.
struct IntervalLower {
  bool operator()(const IntervalNode& a, const IntervalNode& b) const {
    if (a.bound != b.bound) return a.bound < b.bound;
    return keyLess(b.j0, b.ty, b.tx, a.j0, a.ty, a.tx);
  }
};

/// Counts of the work done by expandInterval.
struct IntervalCounts {
  int64_t heading_splits = 0;
  int64_t translation_splits = 0;
  int64_t point_lookups = 0;
};

/// The root layer of the interval search (GlobalSearchOptions::root_layer or the top layer).
int intervalRootLayer(const SearchProblem& problem, const GlobalSearchOptions& options);

/// The typical point's range [cells] (GlobalSearchOptions::typical_range_quantile), deciding
/// which axis a node splits (any choice keeps the search exact).
double typicalRangeCells(const SearchProblem& problem, const GlobalSearchOptions& options);

/// Calls root(j0, heading_level, layer, tx, ty, index) for every root node, index counting
/// from 0 in a fixed order.
template <class RootFn>
void forEachIntervalRoot(const SearchProblem& problem, const GlobalSearchOptions& options,
                         RootFn&& root) {
  const SearchWindow& w = problem.window();
  const int root_layer = intervalRootLayer(problem, options);
  const int root_hl = options.root_heading_levels;
  const int stride = 1 << root_layer;
  int64_t index = 0;
  for (int j0 = 0; j0 < w.sizeH(); j0 += 1 << root_hl) {
    for (int ty = 0; ty < w.sizeY(); ty += stride) {
      for (int tx = 0; tx < w.sizeX(); tx += stride) root(j0, root_hl, root_layer, tx, ty, index++);
    }
  }
}

/// Splits non-leaf `n` (its heading interval while the typical point moves across it by at
/// least heading_split_share of its block, else its translations) and calls push(child) for
/// each child with its bound. bound(j0, heading_level, layer, tx, ty) scores an interval
/// child; count(layer) is called for each child scored exactly on a layer (scoreQuad).
template <class BoundFn, class CountFn, class PushFn>
void expandInterval(const SearchProblem& problem, const GlobalSearchOptions& options,
                    double typical_range, const IntervalNode& n, BoundFn&& bound, CountFn&& count,
                    PushFn&& push, IntervalCounts& counts) {
  const SearchWindow& w = problem.window();
  const int max_layer = problem.map().options().num_layers;
  bool split_heading = n.layer == 0;
  if (n.heading_level > 0 && n.layer > 0) {
    const double half_interval = (1 << (n.heading_level - 1)) * w.heading_step_rad;
    split_heading = typical_range * half_interval >= options.heading_split_share * (1 << n.layer);
  }
  if (n.heading_level > 0 && split_heading) {
    ++counts.heading_splits;
    const int hl = n.heading_level - 1;
    for (int half = 0; half < 2; ++half) {
      const int j0 = n.j0 + half * (1 << hl);
      if (j0 >= w.sizeH()) break;
      push(IntervalNode{bound(j0, hl, n.layer, n.tx, n.ty), j0, n.ty, n.tx, n.layer,
                        static_cast<int16_t>(hl)});
    }
    return;
  }
  ++counts.translation_splits;
  const int child = n.layer - 1;
  const int h = 1 << child;
  int64_t quad[4];
  const bool exact_layer = n.heading_level == 0 && child <= max_layer;
  if (exact_layer) {
    problem.scoreQuad(n.j0, child, n.tx, n.ty, h, quad);
    counts.point_lookups += 4 * problem.preparedPoints(n.j0);
  }
  for (int dy = 0; dy < 2; ++dy) {
    const int ty = n.ty + dy * h;
    if (ty >= w.sizeY()) break;
    for (int dx = 0; dx < 2; ++dx) {
      const int tx = n.tx + dx * h;
      if (tx >= w.sizeX()) break;
      int64_t s;
      if (exact_layer) {
        count(child);
        s = quad[dy * 2 + dx];
      } else {
        s = bound(n.j0, n.heading_level, child, tx, ty);
      }
      push(IntervalNode{s, n.j0, ty, tx, static_cast<int16_t>(child), n.heading_level});
    }
  }
}

}  // namespace search_detail
}  // namespace gmm_localization
