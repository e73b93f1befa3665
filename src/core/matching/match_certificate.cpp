#include "gmm_localization/core/matching/match_certificate.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <vector>

#include "certificate_geometry.h"
#include "search_node.h"

namespace gmm_localization {

std::string CertificateOptions::validate() const {
  if (!(exclusion_radius_m > 0.0 && exclusion_radius_m < 1e4)) {
    return "exclusion_radius_m must be in (0, 1e4)";
  }
  if (!(exclusion_heading_rad > 0.0 && exclusion_heading_rad <= 3.15)) {
    return "exclusion_heading_rad must be in (0, pi]";
  }
  if (!(margin_per_point >= 0.0 && margin_per_point < 100.0)) {
    return "margin_per_point must be in [0, 100)";
  }
  if (!(separation_depth_per_point >= margin_per_point && separation_depth_per_point < 100.0)) {
    return "separation_depth_per_point must be in [margin_per_point, 100)";
  }
  if (max_evaluations < 1) return "max_evaluations must be >= 1";
  if (wide_max_evaluations < 1) return "wide_max_evaluations must be >= 1";
  if (!(wide_min_half_xy_m > 0.0)) return "wide_min_half_xy_m must be > 0";
  if (global_max_evaluations < 1) return "global_max_evaluations must be >= 1";
  return {};
}

const char* certificateFailureName(CertificateFailure failure) {
  switch (failure) {
    case CertificateFailure::kNone:
      return "";
    case CertificateFailure::kDisabled:
      return "disabled";
    case CertificateFailure::kAmbiguous:
      return "ambiguous";
    case CertificateFailure::kWindowEdge:
      return "window_edge";
    case CertificateFailure::kBudget:
      return "budget";
  }
  return "unknown";
}

namespace {

using search_detail::Lower;
using search_detail::Node;

/// The geometry of a node (one heading).
class Geometry {
 public:
  using Extent = search_detail::CertificateGeometry::Extent;
  Geometry(const SearchProblem& problem, const SearchOutcome& optimum, const CertificateOptions& o)
      : g_(problem, optimum, o) {}
  Extent of(const Node& n) const {
    return g_.of(n.tx, n.ty, n.layer, n.heading_index, n.heading_index);
  }

 private:
  search_detail::CertificateGeometry g_;
};

}  // namespace

MatchCertificate certifyOptimum(const SearchProblem& problem, const SearchOutcome& optimum,
                                const CertificateOptions& o, TaskPool* pool) {
  MatchCertificate out;
  if (!o.enabled) return out;
  out.failure = CertificateFailure::kNone;
  const SearchWindow& w = problem.window();
  const ScoreQuantizer q(problem.map().options());
  const double per_point_to_units = static_cast<double>(problem.scanPoints()) / q.step();
  const int64_t best = optimum.score;
  // Deficits in score units, rounded down: a pose exactly at the margin counts as plausible.
  const int64_t margin = static_cast<int64_t>(std::floor(o.margin_per_point * per_point_to_units));
  const int64_t depth =
      static_cast<int64_t>(std::floor(o.separation_depth_per_point * per_point_to_units));
  const int64_t plausible_floor = best - margin;
  const int64_t rival_floor = best - depth;
  const Geometry geometry(problem, optimum, o);

  bool rival_found = false;
  int64_t rival = 0;
  bool border = false;
  // Can the node still change the outcome? A node matters when its bound reaches the
  // plausible floor and it could widen the protection level or touch the border, or while the
  // rival is unknown, when its bound reaches the rival floor and it holds poses elsewhere.
  auto matters = [&](const Node& n, const Geometry::Extent& e) {
    if (n.bound >= plausible_floor &&
        (e.max_xy_m > out.protection_xy_m || e.heading_rad > out.protection_heading_rad ||
         (e.border && !border))) {
      return true;
    }
    return !rival_found && n.bound >= rival_floor && !e.inside;
  };

  std::priority_queue<Node, std::vector<Node>, Lower> queue;
  auto offer = [&](const Node& n) {
    if (matters(n, geometry.of(n))) queue.push(n);
  };

  // The coarsest layer, exhaustively (as the search does).
  const int top = problem.topLayer();
  const int stride = 1 << top;
  // Reused from the branch-and-bound when it kept them (the same layer, the same scores).
  const int nx = (w.sizeX() + stride - 1) / stride, ny = (w.sizeY() + stride - 1) / stride;
  const bool reuse = optimum.top_scores.size() == static_cast<size_t>(nx) * ny * w.sizeH() &&
                     optimum.stats.top_layer == top;
  for (int j = 0; j < w.sizeH(); ++j) {
    for (int ty = 0; ty < w.sizeY(); ty += 2 * stride) {
      for (int tx = 0; tx < w.sizeX(); tx += 2 * stride) {
        int64_t quad[4] = {0, 0, 0, 0};
        if (!reuse) problem.scoreQuad(j, top, tx, ty, stride, quad);
        for (int b = 0; b < 2; ++b) {
          for (int a = 0; a < 2; ++a) {
            const int cx = tx + a * stride, cy = ty + b * stride;
            if (cx >= w.sizeX() || cy >= w.sizeY()) continue;
            int64_t score = quad[b * 2 + a];
            if (reuse) {
              score =
                  optimum
                      .top_scores[(static_cast<size_t>(j) * ny + cy / stride) * nx + cx / stride];
            } else {
              ++out.evaluations;
            }
            offer({score, j, cy, cx, top});
          }
        }
      }
    }
  }

  // Best-first, one node at a time as a single thread would go. With a pool, the children of
  // the node after the popped one are scored beside the popped node's children; they are used
  // only when that node is still the next one popped (nothing pushed meanwhile outranks it),
  // and counted only then: the proof, its evaluations and its budget are the same as on one
  // thread.
  // A node the search branched keeps its children's scores (the same numbers): they are
  // counted as evaluations all the same, so that the proof's budget does not depend on what
  // the search happened to branch (with a pool, that varies from run to run).
  auto expand = [&](const Node& n, int64_t scores[4]) {
    const int h = 1 << (n.layer - 1);
    const int64_t* known = optimum.childScores(n.heading_index, n.layer - 1, n.tx, n.ty);
    if (known != nullptr) {
      std::copy(known, known + 4, scores);
    } else {
      problem.scoreQuad(n.heading_index, n.layer - 1, n.tx, n.ty, h, scores);
    }
  };
  auto sameNode = [](const Node& a, const Node& b) {
    return a.bound == b.bound && a.heading_index == b.heading_index && a.tx == b.tx &&
           a.ty == b.ty && a.layer == b.layer;
  };
  bool have_next = false;  // next_scores holds the children of next_node, scored ahead
  Node next_node{};
  int64_t next_scores[4];
  while (!queue.empty()) {
    if (out.evaluations > o.max_evaluations) {
      out.failure = CertificateFailure::kBudget;
      break;
    }
    const Node n = queue.top();
    queue.pop();
    const Geometry::Extent e = geometry.of(n);
    if (!matters(n, e)) continue;  // the protection level or the rival moved on since the push
    if (n.layer == 0) {
      const bool elsewhere = !e.inside;
      if (elsewhere && !rival_found) {
        // Best-first: no pose elsewhere scores more than the first one popped.
        rival_found = true;
        rival = n.bound;
      }
      if (n.bound >= plausible_floor) {
        out.protection_xy_m = std::max(out.protection_xy_m, e.max_xy_m);
        out.protection_heading_rad = std::max(out.protection_heading_rad, e.heading_rad);
        border = border || e.border;
        if (elsewhere) {
          out.failure = CertificateFailure::kAmbiguous;
          break;
        }
      }
      continue;
    }
    const int child = n.layer - 1;
    const int h = 1 << child;
    int64_t scores[4];
    if (have_next && sameNode(next_node, n)) {
      std::copy(next_scores, next_scores + 4, scores);
      have_next = false;
    } else if (pool != nullptr && !queue.empty() && queue.top().layer > 0) {
      next_node = queue.top();
      pool->run(2, [&](int k) { expand(k == 0 ? n : next_node, k == 0 ? scores : next_scores); });
      have_next = true;
    } else {
      expand(n, scores);
    }
    for (int b = 0; b < 2; ++b) {
      for (int a = 0; a < 2; ++a) {
        const int cx = n.tx + a * h, cy = n.ty + b * h;
        if (cx >= w.sizeX() || cy >= w.sizeY()) continue;
        ++out.evaluations;
        offer({scores[b * 2 + a], n.heading_index, cy, cx, child});
      }
    }
  }

  const double units_to_per_point = q.step() / static_cast<double>(problem.scanPoints());
  out.separation_exact = rival_found;
  out.separation_per_point = rival_found ? static_cast<double>(best - rival) * units_to_per_point
                                         : static_cast<double>(depth) * units_to_per_point;
  if (out.failure == CertificateFailure::kNone && border) {
    out.failure = CertificateFailure::kWindowEdge;
  }
  // The budget may run out after the rival was found and every plausible pose placed: the
  // proof is complete when nothing left in the queue matters.
  if (out.failure == CertificateFailure::kBudget) {
    bool pending = false;
    while (!queue.empty() && !pending) {
      pending = matters(queue.top(), geometry.of(queue.top()));
      queue.pop();
    }
    if (!pending)
      out.failure = border ? CertificateFailure::kWindowEdge : CertificateFailure::kNone;
  }
  out.certified = out.failure == CertificateFailure::kNone;
  return out;
}

}  // namespace gmm_localization
