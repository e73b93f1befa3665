#include "gmm_localization/sim/route.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <set>
#include <sstream>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {
namespace {

using Edge = std::pair<std::pair<int, int>, std::pair<int, int>>;

Edge edgeOf(const GridNode& a, const GridNode& b) { return {{a.i, a.j}, {b.i, b.j}}; }

double edgeLength(const Town& t, const GridNode& a, const GridNode& b) {
  return (t.nodePosition(a.i, a.j) - t.nodePosition(b.i, b.j)).norm();
}

const int kDirs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};

bool inside(const Town& t, const GridNode& n) {
  return n.i >= 0 && n.j >= 0 && n.i < t.nodesX() && n.j < t.nodesY();
}

/// Cheapest way (no U-turns) from (node, heading) to driving one of `targets`; driving an edge
/// again in the same direction costs triple. Returns the nodes after `from` (target included).
std::vector<GridNode> pathToTargets(const Town& town, GridNode from, int heading,
                                    const std::set<Edge>& targets,
                                    const std::map<Edge, int>& driven) {
  const int nx = town.nodesX(), ny = town.nodesY();
  auto id = [&](const GridNode& n, int d) { return (n.j * nx + n.i) * 4 + d; };
  std::vector<double> cost(static_cast<size_t>(nx * ny * 4), 1e300);
  std::vector<int> prev(cost.size(), -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  cost[id(from, heading)] = 0.0;
  open.push({0.0, id(from, heading)});
  while (!open.empty()) {
    const auto [c, s] = open.top();
    open.pop();
    if (c > cost[s]) continue;
    const int d = s % 4, cell = s / 4;
    const GridNode n{cell % nx, cell / nx};
    for (int k = 0; k < 4; ++k) {
      if (k == (d + 2) % 4) continue;
      const GridNode m{n.i + kDirs[k][0], n.j + kDirs[k][1]};
      if (!inside(town, m)) continue;
      const Edge e = edgeOf(n, m);
      if (targets.count(e)) {  // done: unwind
        std::vector<GridNode> path{m, n};
        for (int t = s; prev[t] >= 0; t = prev[t]) {
          const int pc = prev[t] / 4;
          path.push_back({pc % nx, pc / nx});
        }
        path.pop_back();  // `from` itself
        std::reverse(path.begin(), path.end());
        return path;
      }
      const double w = edgeLength(town, n, m) * (driven.count(e) ? 3.0 : 1.0);
      const int t = id(m, k);
      if (c + w < cost[t]) {
        cost[t] = c + w;
        prev[t] = s;
        open.push({cost[t], t});
      }
    }
  }
  return {};
}

/// Alternates short random explorations with drives back over roads already driven, in the
/// other direction, until the length is reached.
std::vector<GridNode> planNodes(const Town& town, const RouteConfig& c) {
  Rng rng(c.seed);
  const int nx = town.nodesX(), ny = town.nodesY();
  GridNode cur{std::min(nx - 1, 1 + rng.uniformInt(std::max(1, nx - 2))),
               std::min(ny - 1, 1 + rng.uniformInt(std::max(1, ny - 2)))};
  int dir = rng.uniformInt(4);
  std::vector<GridNode> nodes{cur};
  std::map<Edge, int> driven;
  double total = 0.0;
  auto drive = [&](const GridNode& next) {
    driven[edgeOf(cur, next)]++;
    total += edgeLength(town, cur, next);
    for (int k = 0; k < 4; ++k)
      if (next.i - cur.i == kDirs[k][0] && next.j - cur.j == kDirs[k][1]) dir = k;
    nodes.push_back(next);
    cur = next;
  };
  const double target = c.length_m + 150.0;  // the path drops half of each end edge
  while (total < target) {
    const int explore = 2 + rng.uniformInt(3);
    for (int step = 0; step < explore && total < target; ++step) {
      double weights[4] = {0, 0, 0, 0}, sum = 0.0;
      for (int k = 0; k < 4; ++k) {
        if (nodes.size() > 1 && k == (dir + 2) % 4) continue;  // no U-turns
        const GridNode next{cur.i + kDirs[k][0], cur.j + kDirs[k][1]};
        if (!inside(town, next)) continue;
        double w = (k == dir) ? 1.5 : 1.0;
        if (driven.count(edgeOf(cur, next))) w *= 0.1;
        weights[k] = w;
        sum += w;
      }
      double pick = rng.uniform() * sum;
      int k = 0;
      while (k < 3 && (weights[k] <= 0.0 || pick >= weights[k])) {
        pick -= weights[k];
        ++k;
      }
      while (weights[k] <= 0.0) k = (k + 3) % 4;  // rounding: fall back to a valid move
      drive({cur.i + kDirs[k][0], cur.j + kDirs[k][1]});
    }
    std::set<Edge> targets;
    for (const auto& e : driven) {
      const Edge rev{e.first.second, e.first.first};
      if (!driven.count(rev)) targets.insert(rev);
    }
    if (targets.empty() || total >= target) continue;
    for (const GridNode& n : pathToTargets(town, cur, dir, targets, driven)) {
      if (total >= target) break;
      drive(n);
    }
  }
  return nodes;
}

}  // namespace

Status RouteConfig::validate() const {
  std::ostringstream os;
  if (!(length_m >= 50.0 && length_m <= 100000.0))
    os << "RouteConfig.length_m = " << length_m << " is outside [50, 100000]";
  else if (!(right_turn_radius_m >= 4.0 && right_turn_radius_m <= 30.0))
    os << "RouteConfig.right_turn_radius_m = " << right_turn_radius_m << " is outside [4, 30]";
  else if (!(left_turn_radius_m >= 4.0 && left_turn_radius_m <= 30.0))
    os << "RouteConfig.left_turn_radius_m = " << left_turn_radius_m << " is outside [4, 30]";
  else if (nodes.size() == 1)
    os << "RouteConfig.nodes: an explicit route needs at least 2 nodes";
  return os.str().empty() ? Status::success() : Status::failure(os.str());
}

Result<Route> Route::plan(const Town& town, const RouteConfig& config) {
  const Status valid = config.validate();
  if (!valid) return Result<Route>::failure(valid.error());
  Route route;
  route.nodes_ = config.nodes.empty() ? planNodes(town, config) : config.nodes;
  const Status built = route.buildPath(town, config);
  if (!built) return Result<Route>::failure(built.error());
  return route;
}

}  // namespace sim
}  // namespace gmm_localization
