#include "gmm_localization/core/matching/global_search.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "search_node.h"

namespace gmm_localization {
namespace {

/// A node: headings [j0, j0 + 2^heading_level), translations [tx, tx + 2^layer) per axis.
struct IntervalNode {
  int64_t bound;
  int32_t j0;
  int32_t ty;
  int32_t tx;
  int16_t layer;
  int16_t heading_level;
};

/// Higher bound first; on equal bounds the smaller first-leaf key (j0, ty, tx) first.
struct IntervalLower {
  bool operator()(const IntervalNode& a, const IntervalNode& b) const {
    if (a.bound != b.bound) return a.bound < b.bound;
    return search_detail::keyLess(b.j0, b.ty, b.tx, a.j0, a.ty, a.tx);
  }
};

int ceilLog2(int64_t n) {
  return n <= 1 ? 0 : 64 - __builtin_clzll(static_cast<unsigned long long>(n - 1));
}

/// Upper bound of the base values over cells [sx, ex) x [sy, ey) at z bin zb, a block no larger
/// than 2^k per axis (global_search.h, RasterWindow::blockBound).
uint8_t blockMax(const RasterWindow& raster, int k, int64_t sx, int64_t sy, int64_t ex, int64_t ey,
                 int32_t zb, int64_t& lookups) {
  ++lookups;
  const MapChunk* c = raster.chunk(sx, sy);
  if (c != nullptr) {
    const int64_t mask = (int64_t{1} << raster.shift()) - 1;
    return c->value(k, zb, static_cast<int>(sx & mask), static_cast<int>(sy & mask));
  }
  if (k == 0) return 0;
  lookups += 3;
  return raster.neighbourBound(k, sx, sy, std::max(ex - sx, ey - sy), zb);
}

/// Offset of the prior's cell from the cells of SearchProblem's points at translation (0, 0).
struct PriorCell {
  int64_t ox;
  int64_t oy;
};

PriorCell priorCell(const SearchProblem& problem) {
  const SearchWindow& w = problem.window();
  const CellIndex c0 = problem.map().geometry().cellAt(w.prior.x, w.prior.y);
  return {c0.x - w.half_x, c0.y - w.half_y};
}

/// Bound on |q| / res of the scan points in cell point p (global_search.h).
double rangeCells(const CellPoint& p, const PriorCell& c) {
  const double dx = std::abs(static_cast<double>(p.gx - c.ox)) + 1.0;
  const double dy = std::abs(static_cast<double>(p.gy - c.oy)) + 1.0;
  return std::sqrt(dx * dx + dy * dy);
}

}  // namespace

std::string GlobalSearchOptions::validate() const {
  if (root_heading_levels < 0 || root_heading_levels > 11) {
    return "root_heading_levels=" + std::to_string(root_heading_levels) + " must be in [0, 11]";
  }
  if (root_layer < -1 || root_layer > 12) {
    return "root_layer=" + std::to_string(root_layer) + " must be -1 or in [0, 12]";
  }
  if (!(heading_split_share > 0.0 && heading_split_share <= 16.0)) {
    return "heading_split_share must be in (0, 16]";
  }
  if (!(typical_range_quantile >= 0.0 && typical_range_quantile <= 1.0)) {
    return "typical_range_quantile must be in [0, 1]";
  }
  if (max_evaluations < 0) return "max_evaluations must be >= 0";
  return {};
}

int64_t headingIntervalBound(const SearchProblem& problem, int j0, int heading_level, int layer,
                             int tx, int ty, int64_t* lookups) {
  const SearchWindow& w = problem.window();
  const int max_layer = problem.map().options().num_layers;
  const int j1 = std::min(j0 + (1 << heading_level), w.sizeH()) - 1;
  const std::vector<CellPoint>& pts = problem.points(j0 + (j1 - j0) / 2);
  if (j0 == j1 && layer <= max_layer) {
    if (lookups != nullptr) *lookups += static_cast<int64_t>(pts.size());
    return problem.score(j0, layer, tx, ty);
  }
  const int jm = j0 + (j1 - j0) / 2;
  const double delta = std::max(jm - j0, j1 - jm) * w.heading_step_rad;
  const RasterWindow& raster = problem.raster();
  const PriorCell prior = priorCell(problem);
  const int64_t block = int64_t{1} << layer;
  int64_t reads = 0;
  int64_t sum = 0;
  for (const CellPoint& p : pts) {
    const int64_t m =
        delta > 0.0 ? static_cast<int64_t>(std::ceil(rangeCells(p, prior) * delta + 1e-6)) : 0;
    const int64_t n = block + 2 * m;  // cells per axis the point can read
    const int k = std::min(max_layer, ceilLog2(n));
    const int64_t b = int64_t{1} << k;
    const int64_t nb = (n + b - 1) / b;
    if (nb > 4) {  // too spread out to be worth 25+ reads: the largest value any cell holds
      sum += static_cast<int64_t>(p.count) * 255;
      continue;
    }
    const int64_t sx = int64_t{p.gx} + tx - m, sy = int64_t{p.gy} + ty - m;
    uint8_t v = 0;
    for (int64_t by = 0; by < nb; ++by) {
      const int64_t y0 = sy + by * b, y1 = std::min(y0 + b, sy + n);
      for (int64_t bx = 0; bx < nb; ++bx) {
        const int64_t x0 = sx + bx * b, x1 = std::min(x0 + b, sx + n);
        v = std::max(v, blockMax(raster, k, x0, y0, x1, y1, p.zb, reads));
      }
    }
    sum += static_cast<int64_t>(p.count) * v;
  }
  if (lookups != nullptr) *lookups += reads;
  return sum;
}

GlobalSearchOutcome globalBranchAndBound(const SearchProblem& problem,
                                         const GlobalSearchOptions& options) {
  const SearchWindow& w = problem.window();
  const int max_layer = problem.map().options().num_layers;
  const int root_layer = options.root_layer < 0 ? problem.topLayer() : options.root_layer;
  const int root_hl = options.root_heading_levels;
  GlobalSearchOutcome out;
  SearchStats stats;
  stats.exhaustive_poses = w.poses();
  stats.top_layer = root_layer;
  stats.evaluations_per_layer.assign(std::max(root_layer, max_layer) + 1, 0);

  // The typical point's range [cells], deciding which axis a node splits (any choice is exact).
  double typical_range = 0.0;
  {
    const PriorCell prior = priorCell(problem);
    std::vector<double> r;
    for (const CellPoint& p : problem.points(w.half_h)) r.push_back(rangeCells(p, prior));
    if (!r.empty()) {
      const size_t i = std::min(
          r.size() - 1, static_cast<size_t>(options.typical_range_quantile * (r.size() - 1)));
      std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(i), r.end());
      typical_range = r[i];
    }
  }

  auto bound = [&](int j0, int hl, int layer, int tx, int ty) {
    ++stats.evaluations;
    ++stats.evaluations_per_layer[layer];
    return headingIntervalBound(problem, j0, hl, layer, tx, ty, &out.point_lookups);
  };
  int64_t incumbent = -1;
  if (options.prior_as_incumbent) incumbent = bound(w.half_h, 0, 0, w.half_x, w.half_y);

  std::priority_queue<IntervalNode, std::vector<IntervalNode>, IntervalLower> queue;
  auto push = [&](const IntervalNode& n) {
    if (n.bound < incumbent) return;
    queue.push(n);
    stats.queue_peak = std::max<int64_t>(stats.queue_peak, static_cast<int64_t>(queue.size()));
  };
  const int stride = 1 << root_layer;
  for (int j0 = 0; j0 < w.sizeH(); j0 += 1 << root_hl) {
    for (int ty = 0; ty < w.sizeY(); ty += stride) {
      for (int tx = 0; tx < w.sizeX(); tx += stride) {
        push({bound(j0, root_hl, root_layer, tx, ty), j0, ty, tx, static_cast<int16_t>(root_layer),
              static_cast<int16_t>(root_hl)});
      }
    }
  }

  while (!queue.empty()) {
    const IntervalNode n = queue.top();
    queue.pop();
    if (n.layer == 0 && n.heading_level == 0) {
      out.best = search_detail::makeOutcome(problem, n.j0, n.tx, n.ty, n.bound, std::move(stats));
      return out;
    }
    if (options.max_evaluations > 0 && stats.evaluations >= options.max_evaluations) break;
    bool split_heading = n.layer == 0;
    if (n.heading_level > 0 && n.layer > 0) {
      const double half_interval = (1 << (n.heading_level - 1)) * w.heading_step_rad;
      split_heading = typical_range * half_interval >= options.heading_split_share * (1 << n.layer);
    }
    if (n.heading_level > 0 && split_heading) {
      ++out.heading_splits;
      const int hl = n.heading_level - 1;
      for (int half = 0; half < 2; ++half) {
        const int j0 = n.j0 + half * (1 << hl);
        if (j0 >= w.sizeH()) break;
        push({bound(j0, hl, n.layer, n.tx, n.ty), j0, n.ty, n.tx, n.layer,
              static_cast<int16_t>(hl)});
      }
      continue;
    }
    ++out.translation_splits;
    const int child = n.layer - 1;
    const int h = 1 << child;
    int64_t quad[4];
    const bool exact_layer = n.heading_level == 0 && child <= max_layer;
    if (exact_layer) {
      problem.scoreQuad(n.j0, child, n.tx, n.ty, h, quad);
      out.point_lookups += 4 * static_cast<int64_t>(problem.points(n.j0).size());
    }
    for (int dy = 0; dy < 2; ++dy) {
      const int ty = n.ty + dy * h;
      if (ty >= w.sizeY()) break;
      for (int dx = 0; dx < 2; ++dx) {
        const int tx = n.tx + dx * h;
        if (tx >= w.sizeX()) break;
        int64_t s;
        if (exact_layer) {
          ++stats.evaluations;
          ++stats.evaluations_per_layer[child];
          s = quad[dy * 2 + dx];
        } else {
          s = bound(n.j0, n.heading_level, child, tx, ty);
        }
        push({s, n.j0, ty, tx, static_cast<int16_t>(child), n.heading_level});
      }
    }
  }
  // Budget reached (or, were a bound not admissible, nothing left): the prior, not an optimum.
  out.complete = false;
  out.best = search_detail::makeOutcome(problem, w.half_h, w.half_x, w.half_y,
                                        std::max<int64_t>(incumbent, 0), std::move(stats));
  return out;
}

}  // namespace gmm_localization
