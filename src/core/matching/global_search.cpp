#include "gmm_localization/core/matching/global_search.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "interval_node.h"

namespace gmm_localization {
namespace {

using search_detail::IntervalCounts;
using search_detail::IntervalLower;
using search_detail::IntervalNode;

int floorLog2(int64_t n) {
  return n <= 1 ? 0 : 63 - __builtin_clzll(static_cast<unsigned long long>(n));
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

/// A table read in flight: the cell's span, then (once the span is read) the value's address.
struct PendingRead {
  const uint32_t* span;  ///< begin, first z bin, next cell's begin
  const uint8_t* value;  ///< the layer's values, then the value read (nullptr: the floor)
  int32_t z;             ///< the point's z bin in the layer's units
  uint32_t point;
};

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

namespace search_detail {

int intervalRootLayer(const SearchProblem& problem, const GlobalSearchOptions& options) {
  return options.root_layer < 0 ? problem.topLayer() : options.root_layer;
}

double typicalRangeCells(const SearchProblem& problem, const GlobalSearchOptions& options) {
  const PriorCell prior = priorCell(problem);
  std::vector<double> r;
  for (const CellPoint& p : problem.points(problem.window().half_h)) {
    r.push_back(rangeCells(p, prior));
  }
  if (r.empty()) return 0.0;
  const size_t i =
      std::min(r.size() - 1, static_cast<size_t>(options.typical_range_quantile * (r.size() - 1)));
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(i), r.end());
  return r[i];
}

}  // namespace search_detail

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
  if (std::isnan(min_score_per_point) ||
      min_score_per_point == std::numeric_limits<double>::infinity()) {
    return "min_score_per_point must be a number or -inf (off)";
  }
  if (queues < 0 || queues > 64) return "queues=" + std::to_string(queues) + " must be in [0, 64]";
  if (threads < 0 || threads > 64) {
    return "threads=" + std::to_string(threads) + " must be in [0, 64]";
  }
  if (!(confirm_half_xy_m > 0.0 && confirm_half_xy_m <= 12.5)) {
    return "confirm_half_xy_m must be in (0, 12.5]";
  }
  if (!(confirm_half_heading_rad > 0.0 && confirm_half_heading_rad <= 0.5)) {
    return "confirm_half_heading_rad must be in (0, 0.5]";
  }
  if (max_reads_per_point < 1 || max_reads_per_point > 16) {
    return "max_reads_per_point=" + std::to_string(max_reads_per_point) + " must be in [1, 16]";
  }
  return {};
}

namespace {

/// headingIntervalBound's sum over one channel's points (global_search.h; the channels' bounds
/// add up, search_problem.h), for headings [j0, j1] around jm.
int64_t channelIntervalBound(const SearchProblem& problem, int channel, int j0, int j1, int layer,
                             int tx, int ty, int64_t* lookups, int max_reads_per_point) {
  const SearchWindow& w = problem.window();
  const int max_layer = problem.map().options().num_layers;
  const int jm = j0 + (j1 - j0) / 2;
  const std::vector<CellPoint>& pts = problem.points(jm, channel);
  const double delta = std::max(jm - j0, j1 - jm) * w.heading_step_rad;
  // Per-axis reach of a rotation by at most delta (global_search.h): |cos a - 1| <= 1 - cos delta
  // for delta <= pi, |sin a| <= sin delta for delta <= pi / 2 (else 1, and 2 for the cosine).
  const double cos_reach = delta < M_PI ? 1.0 - std::cos(delta) : 2.0;
  const double sin_reach = delta < M_PI / 2 ? std::sin(delta) : 1.0;
  const RasterWindow& raster = problem.raster(channel);
  const PriorCell prior = priorCell(problem);
  const int64_t block = int64_t{1} << layer;
  const int max_reads = std::max(1, max_reads_per_point);
  const int64_t mask = (int64_t{1} << raster.shift()) - 1;
  // Three passes, so that the table reads of all points are in flight together (each read is
  // two dependent cache misses, the span then the value): addresses and span prefetches, then
  // value prefetches, then the maxima.
  thread_local std::vector<PendingRead> pending;
  thread_local std::vector<uint8_t> point_max;
  pending.clear();
  point_max.assign(pts.size(), 0);
  int64_t reads = 0;
  for (size_t pi = 0; pi < pts.size(); ++pi) {
    const CellPoint& p = pts[pi];
    int64_t mx = 0, my = 0;
    if (delta > 0.0) {
      const double ax = std::abs(static_cast<double>(p.gx - prior.ox)) + 1.0;
      const double ay = std::abs(static_cast<double>(p.gy - prior.oy)) + 1.0;
      const double chord = std::hypot(ax, ay) * delta;
      mx = static_cast<int64_t>(std::ceil(std::min(chord, ax * cos_reach + ay * sin_reach) + 1e-6));
      my = static_cast<int64_t>(std::ceil(std::min(chord, ay * cos_reach + ax * sin_reach) + 1e-6));
    }
    // The rectangle the point can read, nx x ny cells from (sx, sy), covered by blocks of layer
    // k: sliding-window maxima, so blocks may overlap and the last one ends at the edge.
    const int64_t nx = block + 2 * mx, ny = block + 2 * my;
    int k = std::min(max_layer, floorLog2(std::min(nx, ny)));
    int64_t b = int64_t{1} << k;
    int64_t cx = (nx + b - 1) / b, cy = (ny + b - 1) / b;
    while (cx * cy > max_reads && k < max_layer) {
      ++k;
      b <<= 1;
      cx = (nx + b - 1) / b;
      cy = (ny + b - 1) / b;
    }
    if (cx * cy > 16) {  // too spread out to be worth the reads: the largest value any cell holds
      point_max[pi] = 255;
      continue;
    }
    const int64_t sx = int64_t{p.gx} + tx - mx, sy = int64_t{p.gy} + ty - my;
    for (int64_t iy = 0; iy < cy; ++iy) {
      const int64_t y0 = iy + 1 < cy ? sy + iy * b : std::max(sy, sy + ny - b);
      for (int64_t ix = 0; ix < cx; ++ix) {
        const int64_t x0 = ix + 1 < cx ? sx + ix * b : std::max(sx, sx + nx - b);
        const MapChunk* c = raster.chunk(x0, y0);
        if (c == nullptr) {  // rare: the block starts in a chunk that is not loaded
          const int64_t x1 = std::min(x0 + b, sx + nx), y1 = std::min(y0 + b, sy + ny);
          point_max[pi] = std::max(point_max[pi], blockMax(raster, k, x0, y0, x1, y1, p.zb, reads));
          continue;
        }
        ++reads;
        const RasterLayer& L = c->layer(k);
        const size_t i =
            (static_cast<size_t>(y0 & mask) << raster.shift()) + static_cast<size_t>(x0 & mask);
        const uint32_t* span = L.spans + 2 * i;
        __builtin_prefetch(span);
        pending.push_back({span, L.values, p.zb >> L.z_shift, static_cast<uint32_t>(pi)});
      }
    }
  }
  for (PendingRead& r : pending) {
    const uint32_t begin = r.span[0];
    const uint32_t n = r.span[2] - begin;
    const uint32_t z = static_cast<uint32_t>(r.z - static_cast<int32_t>(r.span[1]));
    r.value = z < n ? r.value + begin + z : nullptr;  // outside the stored span: the floor
    if (r.value != nullptr) __builtin_prefetch(r.value);
  }
  for (const PendingRead& r : pending) {
    if (r.value != nullptr) point_max[r.point] = std::max(point_max[r.point], *r.value);
  }
  int64_t sum = 0;
  for (size_t pi = 0; pi < pts.size(); ++pi) {
    sum += static_cast<int64_t>(pts[pi].count) * point_max[pi];
  }
  if (lookups != nullptr) *lookups += reads;
  return sum;
}

}  // namespace

int64_t headingIntervalBound(const SearchProblem& problem, int j0, int heading_level, int layer,
                             int tx, int ty, int64_t* lookups, int max_reads_per_point) {
  const int max_layer = problem.map().options().num_layers;
  const int j1 = std::min(j0 + (1 << heading_level), problem.window().sizeH()) - 1;
  if (j0 == j1 && layer <= max_layer) {
    if (lookups != nullptr) *lookups += problem.preparedPoints(j0);
    return problem.score(j0, layer, tx, ty);
  }
  int64_t sum = 0;
  for (int c = 0; c < problem.numChannels(); ++c) {
    sum += channelIntervalBound(problem, c, j0, j1, layer, tx, ty, lookups, max_reads_per_point);
  }
  return sum;
}

namespace {

/// What one queue of the search found: its best leaf (when it popped one) and its counts.
struct QueueResult {
  bool found = false;
  IntervalNode leaf{};
  SearchStats stats;
  int64_t heading_splits = 0;
  int64_t translation_splits = 0;
  int64_t point_lookups = 0;
  std::vector<SearchOutcome::IntervalBound> bounds;  ///< every node bound it computed
};

/// min_score_per_point in score units for the problem's points, rounded up (a leaf below it
/// scores below the floor per point); -1 when the floor is off (at or below the map's own, or
/// a problem of two channels: the floor was measured on the height likelihood alone).
int64_t floorScore(const SearchProblem& problem, double per_point) {
  const ScoreQuantizer q(problem.map().options());
  if (problem.numChannels() > 1 || !(per_point > q.floor())) return -1;
  return static_cast<int64_t>(
      std::ceil((per_point - q.floor()) / q.step() * static_cast<double>(problem.scanPoints())));
}

/// State the queues share: the best leaf score proven so far (the pruning threshold) and the
/// node budget.
struct SharedSearch {
  std::atomic<int64_t> incumbent{-1};
  std::atomic<int64_t> evaluations{0};
  std::atomic<bool> budget_hit{false};
  std::atomic<bool> cancelled{false};
  const std::atomic<bool>* cancel = nullptr;  ///< the caller's flag (may be null)

  void raise(int64_t score) {
    int64_t cur = incumbent.load();
    while (score > cur && !incumbent.compare_exchange_weak(cur, score)) {
    }
  }
};

/// Best-first branch-and-bound over the roots r with r % queues == q.
QueueResult searchQueue(const SearchProblem& problem, const GlobalSearchOptions& options,
                        double typical_range, int q, int queues, SharedSearch& shared) {
  const int max_layer = problem.map().options().num_layers;
  const int root_layer = search_detail::intervalRootLayer(problem, options);
  QueueResult out;
  out.stats.evaluations_per_layer.assign(std::max(root_layer, max_layer) + 1, 0);
  auto count = [&](int layer) {
    ++out.stats.evaluations;
    ++out.stats.evaluations_per_layer[layer];
    const int64_t total = shared.evaluations.fetch_add(1) + 1;
    if (options.max_evaluations > 0 && total >= options.max_evaluations) {
      shared.budget_hit = true;
    }
    if (shared.cancel != nullptr && shared.cancel->load(std::memory_order_relaxed)) {
      shared.cancelled = true;
      shared.budget_hit = true;
    }
  };
  auto bound = [&](int j0, int hl, int layer, int tx, int ty) {
    count(layer);
    const int64_t b = headingIntervalBound(problem, j0, hl, layer, tx, ty, &out.point_lookups,
                                           options.max_reads_per_point);
    out.bounds.push_back({SearchOutcome::intervalKey(j0, hl, layer, tx, ty), b});
    return b;
  };
  std::priority_queue<IntervalNode, std::vector<IntervalNode>, IntervalLower> queue;
  auto push = [&](const IntervalNode& n) {
    if (n.bound < shared.incumbent.load(std::memory_order_relaxed)) return;
    queue.push(n);
    out.stats.queue_peak =
        std::max<int64_t>(out.stats.queue_peak, static_cast<int64_t>(queue.size()));
  };
  search_detail::forEachIntervalRoot(
      problem, options, [&](int j0, int hl, int layer, int tx, int ty, int64_t index) {
        if (index % queues != q) return;
        push({bound(j0, hl, layer, tx, ty), j0, ty, tx, static_cast<int16_t>(layer),
              static_cast<int16_t>(hl)});
      });

  IntervalCounts counts;
  while (!queue.empty()) {
    const IntervalNode n = queue.top();
    queue.pop();
    // Everything left is below a leaf another queue proved: nothing here can win.
    if (n.bound < shared.incumbent.load(std::memory_order_relaxed)) break;
    if (n.leaf()) {
      out.found = true;
      out.leaf = n;
      shared.raise(n.bound);
      break;
    }
    if (shared.budget_hit.load(std::memory_order_relaxed)) break;
    search_detail::expandInterval(problem, options, typical_range, n, bound, count, push, counts);
  }
  out.heading_splits += counts.heading_splits;
  out.translation_splits += counts.translation_splits;
  out.point_lookups += counts.point_lookups;
  return out;
}

}  // namespace

GlobalSearchOutcome globalBranchAndBound(const SearchProblem& problem,
                                         const GlobalSearchOptions& options, TaskPool* pool,
                                         const std::atomic<bool>* cancel) {
  const SearchWindow& w = problem.window();
  const int max_layer = problem.map().options().num_layers;
  const int root_layer = search_detail::intervalRootLayer(problem, options);
  GlobalSearchOutcome out;
  SearchStats stats;
  stats.exhaustive_poses = w.poses();
  stats.top_layer = root_layer;
  stats.evaluations_per_layer.assign(std::max(root_layer, max_layer) + 1, 0);

  const double typical_range = search_detail::typicalRangeCells(problem, options);

  SharedSearch shared;
  shared.cancel = cancel;
  int64_t prior_score = -1;
  if (options.prior_as_incumbent) {
    prior_score = headingIntervalBound(problem, w.half_h, 0, 0, w.half_x, w.half_y,
                                       &out.point_lookups, options.max_reads_per_point);
    ++stats.evaluations;
    ++stats.evaluations_per_layer[0];
    shared.evaluations = 1;
    shared.incumbent = prior_score;
  }
  const int64_t floor_score = floorScore(problem, options.min_score_per_point);
  if (floor_score > shared.incumbent.load()) shared.incumbent = floor_score;
  // The queues share the best leaf score proven so far; each pops its own best-first and stops
  // when its best bound falls below it. The optimum: the best leaf over the queues, the
  // smallest key among equal scores (global_search.h), for any number of queues.
  const int queues = options.queues > 0 ? options.queues : (pool != nullptr ? pool->threads() : 1);
  std::vector<QueueResult> results(static_cast<size_t>(queues));
  parallelFor(pool, queues, [&](int q) {
    results[static_cast<size_t>(q)] =
        searchQueue(problem, options, typical_range, q, queues, shared);
  });
  const QueueResult* best = nullptr;
  for (const QueueResult& r : results) {
    stats.evaluations += r.stats.evaluations;
    for (size_t l = 0; l < r.stats.evaluations_per_layer.size(); ++l) {
      stats.evaluations_per_layer[l] += r.stats.evaluations_per_layer[l];
    }
    stats.queue_peak += r.stats.queue_peak;
    out.heading_splits += r.heading_splits;
    out.translation_splits += r.translation_splits;
    out.point_lookups += r.point_lookups;
    if (!r.found) continue;
    if (best == nullptr || r.leaf.bound > best->leaf.bound ||
        (r.leaf.bound == best->leaf.bound &&
         search_detail::keyLess(r.leaf.j0, r.leaf.ty, r.leaf.tx, best->leaf.j0, best->leaf.ty,
                                best->leaf.tx))) {
      best = &r;
    }
  }
  if (best != nullptr && !shared.budget_hit) {
    out.best = search_detail::makeOutcome(problem, best->leaf.j0, best->leaf.tx, best->leaf.ty,
                                          best->leaf.bound, std::move(stats));
    // The queues score disjoint subtrees of distinct roots: every key appears once.
    std::vector<SearchOutcome::IntervalBound>& all = out.best.interval_bounds;
    for (const QueueResult& r : results) all.insert(all.end(), r.bounds.begin(), r.bounds.end());
    search_detail::sortByKey(all);
    return out;
  }
  // Budget reached or cancelled, or nothing reached the floor (or, were a bound not admissible,
  // nothing left): the prior, not an optimum.
  out.complete = false;
  out.cancelled = shared.cancelled;
  out.below_floor = best == nullptr && !shared.budget_hit && floor_score > prior_score;
  out.best = search_detail::makeOutcome(problem, w.half_h, w.half_x, w.half_y,
                                        std::max<int64_t>(prior_score, 0), std::move(stats));
  return out;
}

}  // namespace gmm_localization
