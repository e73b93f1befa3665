#include "gmm_localization/core/matching/global_certificate.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <queue>
#include <vector>

#include "certificate_geometry.h"
#include "interval_node.h"

namespace gmm_localization {
namespace {

using search_detail::IntervalLower;
using search_detail::IntervalNode;

/// The geometry of an interval node.
class IntervalGeometry {
 public:
  using Extent = search_detail::CertificateGeometry::Extent;
  IntervalGeometry(const SearchProblem& problem, const SearchOutcome& optimum,
                   const CertificateOptions& o)
      : window_(problem.window()), g_(problem, optimum, o) {}
  Extent of(const IntervalNode& n) const {
    const int j1 = std::min(n.j0 + (1 << n.heading_level), window_.sizeH()) - 1;
    return g_.of(n.tx, n.ty, n.layer, n.j0, j1);
  }

 private:
  const SearchWindow& window_;
  search_detail::CertificateGeometry g_;
};

/// What one queue of the proof found.
struct QueueProof {
  double protection_xy_m = 0.0;
  double protection_heading_rad = 0.0;
  bool border = false;
  bool ambiguous = false;
  bool pending = false;  ///< stopped at the budget with nodes that still matter
};

/// State the queues share: the node count (for the budget), the stop on ambiguity or on the
/// caller's cancel flag, and whether the cancel flag stopped it.
struct SharedProof {
  std::atomic<int64_t> evaluations{0};
  std::atomic<bool> stop{false};
  std::atomic<bool> cancelled{false};
  const std::atomic<bool>* cancel = nullptr;  ///< the caller's flag (may be null)
};

/// Best-first proof over the roots r with r % queues == q: every node whose bound reaches
/// `floor` and that can widen the queue's protection level, touch the border or hold a pose
/// elsewhere is split, down to the leaves.
QueueProof proveQueue(const SearchProblem& problem, const SearchOutcome& optimum,
                      const GlobalSearchOptions& search, const IntervalGeometry& geometry,
                      int64_t floor, int64_t budget, double typical_range, int q, int queues,
                      SharedProof& shared) {
  QueueProof out;
  auto matters = [&](const IntervalNode& n, const IntervalGeometry::Extent& e) {
    return n.bound >= floor &&
           (!e.inside || e.max_xy_m > out.protection_xy_m ||
            e.heading_rad > out.protection_heading_rad || (e.border && !out.border));
  };
  std::priority_queue<IntervalNode, std::vector<IntervalNode>, IntervalLower> queue;
  auto push = [&](const IntervalNode& n) {
    if (matters(n, geometry.of(n))) queue.push(n);
  };
  auto count = [&](int) { shared.evaluations.fetch_add(1, std::memory_order_relaxed); };
  // A node the search scored keeps its bound (the same number): counted all the same, so that
  // the budget does not depend on what the search's queues happened to score.
  auto bound = [&](int j0, int hl, int layer, int tx, int ty) {
    count(layer);
    const int64_t* known = optimum.intervalBound(j0, hl, layer, tx, ty);
    return known != nullptr ? *known
                            : headingIntervalBound(problem, j0, hl, layer, tx, ty, nullptr,
                                                   search.max_reads_per_point);
  };
  search_detail::forEachIntervalRoot(
      problem, search, [&](int j0, int hl, int layer, int tx, int ty, int64_t index) {
        if (index % queues != q) return;
        push({bound(j0, hl, layer, tx, ty), j0, ty, tx, static_cast<int16_t>(layer),
              static_cast<int16_t>(hl)});
      });
  search_detail::IntervalCounts counts;
  while (!queue.empty() && !shared.stop.load(std::memory_order_relaxed)) {
    if (shared.cancel != nullptr && shared.cancel->load(std::memory_order_relaxed)) {
      shared.cancelled = true;
      shared.stop = true;
      break;
    }
    const IntervalNode n = queue.top();
    queue.pop();
    const IntervalGeometry::Extent e = geometry.of(n);
    if (!matters(n, e)) continue;  // the protection level moved on since the push
    if (n.leaf()) {
      out.protection_xy_m = std::max(out.protection_xy_m, e.max_xy_m);
      out.protection_heading_rad = std::max(out.protection_heading_rad, e.heading_rad);
      out.border = out.border || e.border;
      if (!e.inside) {
        out.ambiguous = true;
        shared.stop = true;
      }
      continue;
    }
    if (shared.evaluations.load(std::memory_order_relaxed) > budget) {
      out.pending = true;  // this node still matters
      break;
    }
    search_detail::expandInterval(problem, search, typical_range, n, bound, count, push, counts);
  }
  return out;
}

}  // namespace

MatchCertificate certifyGlobalOptimum(const SearchProblem& problem, const SearchOutcome& optimum,
                                      const CertificateOptions& o,
                                      const GlobalSearchOptions& search, TaskPool* pool,
                                      const std::atomic<bool>* cancel, bool* cancelled) {
  MatchCertificate out;
  if (cancelled != nullptr) *cancelled = false;
  if (!o.enabled) return out;
  const ScoreQuantizer q(problem.map().options());
  const double per_point_to_units = static_cast<double>(problem.scanPoints()) / q.step();
  // The plausible floor in score units, rounded down: a pose exactly at the margin counts. The
  // separation is proved down to the margin only (not to separation_depth_per_point: deeper,
  // the proof over a global window costs several times more), so a pose elsewhere above the
  // floor is both the rival and the reason for "ambiguous".
  const int64_t margin = static_cast<int64_t>(std::floor(o.margin_per_point * per_point_to_units));
  const int64_t floor = optimum.score - margin;
  const IntervalGeometry geometry(problem, optimum, o);
  const double typical_range = search_detail::typicalRangeCells(problem, search);
  const int queues = search.queues > 0 ? search.queues : (pool != nullptr ? pool->threads() : 1);
  SharedProof shared;
  shared.cancel = cancel;
  std::vector<QueueProof> proofs(static_cast<size_t>(queues));
  parallelFor(pool, queues, [&](int k) {
    proofs[static_cast<size_t>(k)] =
        proveQueue(problem, optimum, search, geometry, floor, o.global_max_evaluations,
                   typical_range, k, queues, shared);
  });
  bool border = false, ambiguous = false, pending = false;
  for (const QueueProof& p : proofs) {
    out.protection_xy_m = std::max(out.protection_xy_m, p.protection_xy_m);
    out.protection_heading_rad = std::max(out.protection_heading_rad, p.protection_heading_rad);
    border = border || p.border;
    ambiguous = ambiguous || p.ambiguous;
    pending = pending || p.pending;
  }
  out.evaluations = shared.evaluations.load();
  if (cancelled != nullptr) *cancelled = shared.cancelled;
  // Cancelled: unproved, as a proof stopped at its budget.
  out.failure = shared.cancelled ? CertificateFailure::kBudget
                : ambiguous      ? CertificateFailure::kAmbiguous
                : pending        ? CertificateFailure::kBudget
                : border         ? CertificateFailure::kWindowEdge
                                 : CertificateFailure::kNone;
  out.certified = out.failure == CertificateFailure::kNone;
  out.separation_exact = false;  // a lower bound: the margin (or 0 when ambiguous)
  out.separation_per_point = ambiguous ? 0.0
                                       : static_cast<double>(margin) * q.step() /
                                             static_cast<double>(problem.scanPoints());
  return out;
}

}  // namespace gmm_localization
