// Route lane path: lines along the outer right lane and tangent circular arcs at turns.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "gmm_localization/sim/route.h"

namespace gmm_localization {
namespace sim {

Status Route::buildPath(const Town& town, const RouteConfig& config) {
  if (nodes_.size() < 2) return Status::failure("route: fewer than 2 nodes");
  const double off = town.laneOffsets().outer_m;
  std::vector<Eigen::Vector2d> dirs;
  for (size_t k = 0; k + 1 < nodes_.size(); ++k) {
    const GridNode a = nodes_[k], b = nodes_[k + 1];
    for (const GridNode& n : {a, b}) {
      if (n.i < 0 || n.j < 0 || n.i >= town.nodesX() || n.j >= town.nodesY()) {
        std::ostringstream os;
        os << "route: node (" << n.i << ", " << n.j << ") is outside the " << town.nodesX() << " x "
           << town.nodesY() << " grid";
        return Status::failure(os.str());
      }
    }
    if (std::abs(a.i - b.i) + std::abs(a.j - b.j) != 1) {
      std::ostringstream os;
      os << "route: nodes " << k << " and " << k + 1 << " are not adjacent";
      return Status::failure(os.str());
    }
    dirs.push_back((town.nodePosition(b.i, b.j) - town.nodePosition(a.i, a.j)).normalized());
    if (k > 0 && dirs[k].dot(dirs[k - 1]) < -0.5)
      return Status::failure("route: U-turn at node " + std::to_string(k));
  }
  auto right = [](const Eigen::Vector2d& d) { return Eigen::Vector2d(d.y(), -d.x()); };
  auto node = [&](size_t k) { return town.nodePosition(nodes_[k].i, nodes_[k].j); };

  pieces_.clear();
  stations_.clear();
  double s = 0.0;
  Eigen::Vector2d cur = 0.5 * (node(0) + node(1)) + right(dirs[0]) * off;
  auto addLine = [&](const Eigen::Vector2d& to, const Eigen::Vector2d& d) {
    const double len = (to - cur).dot(d);
    if (len > 1e-9) pieces_.push_back({s, len, cur, std::atan2(d.y(), d.x()), 0.0});
    s += std::max(0.0, len);
    cur = to;
  };
  for (size_t k = 1; k + 1 < nodes_.size(); ++k) {
    const Eigen::Vector2d din = dirs[k - 1], dout = dirs[k];
    const double cross = din.x() * dout.y() - din.y() * dout.x();
    if (std::abs(cross) < 0.5) {  // straight through
      const Eigen::Vector2d pass = node(k) + right(din) * off;
      addLine(pass, din);
      stations_.push_back(s);
      continue;
    }
    const bool left = cross > 0.0;
    const double r = left ? config.left_turn_radius_m : config.right_turn_radius_m;
    const Eigen::Vector2d corner = node(k) + right(din) * off + right(dout) * off;
    addLine(corner - din * r, din);
    const double kappa = left ? 1.0 / r : -1.0 / r;
    const double arc = 0.5 * M_PI * r;
    pieces_.push_back({s, arc, cur, std::atan2(din.y(), din.x()), kappa});
    stations_.push_back(s + 0.5 * arc);
    s += arc;
    cur = corner + dout * r;
  }
  const Eigen::Vector2d dlast = dirs.back();
  addLine(0.5 * (node(nodes_.size() - 2) + node(nodes_.size() - 1)) + right(dlast) * off, dlast);
  length_ = s;

  // Share of driven road length whose reverse is driven too.
  std::map<std::pair<std::pair<int, int>, std::pair<int, int>>, double> len;
  for (size_t k = 0; k + 1 < nodes_.size(); ++k)
    len[{{nodes_[k].i, nodes_[k].j}, {nodes_[k + 1].i, nodes_[k + 1].j}}] =
        (node(k + 1) - node(k)).norm();
  double both = 0.0, all = 0.0;
  for (const auto& e : len) {
    all += e.second;
    if (len.count({e.first.second, e.first.first})) both += e.second;
  }
  both_share_ = all > 0.0 ? both / all : 0.0;
  return Status::success();
}

PathPoint Route::at(double s) const {
  s = std::clamp(s, 0.0, length_);
  auto it = std::upper_bound(pieces_.begin(), pieces_.end(), s,
                             [](double v, const Piece& p) { return v < p.s0; });
  const Piece& p = (it == pieces_.begin()) ? pieces_.front() : *(it - 1);
  const double u = std::min(s - p.s0, p.length);
  PathPoint out;
  out.curvature = p.curvature;
  if (p.curvature == 0.0) {
    out.heading_rad = p.heading0;
    out.position = p.start + u * Eigen::Vector2d(std::cos(p.heading0), std::sin(p.heading0));
  } else {
    const double th = p.heading0 + p.curvature * u;
    out.heading_rad = th;
    out.position = p.start + Eigen::Vector2d(std::sin(th) - std::sin(p.heading0),
                                             std::cos(p.heading0) - std::cos(th)) /
                                 p.curvature;
  }
  return out;
}

}  // namespace sim
}  // namespace gmm_localization
