#include "gmm_localization/ros/map_server_cloud.h"

namespace gmm_localization {
namespace node {

void buildMapCloud(const std::vector<MapChunkConstPtr>& chunks, const MapGeometry& geometry,
                   const std::vector<PlanCentre>& centres, double radius_m, CloudData& cloud,
                   std::vector<float>& sigma_m) {
  cloud = CloudData();
  sigma_m.clear();
  const double r2 = radius_m * radius_m;
  auto near = [&](const Eigen::Vector2d& p) {
    for (const PlanCentre& c : centres) {
      if ((p - c).squaredNorm() <= r2) return true;
    }
    return false;
  };
  for (const MapChunkConstPtr& chunk : chunks) {
    if (!chunk || !chunk->hasMixtures()) continue;
    const CellIndex o = chunk->origin();
    const int n = chunk->cells();
    // Skip whole chunks out of reach (their nearest point is farther than the radius).
    const Eigen::Vector2d lo = geometry.cellCenter(o);
    const Eigen::Vector2d hi = geometry.cellCenter({o.x + n - 1, o.y + n - 1});
    bool chunk_near = false;
    for (const PlanCentre& c : centres) {
      const Eigen::Vector2d q = c.cwiseMax(lo).cwiseMin(hi);
      chunk_near = chunk_near || (q - c).squaredNorm() <= r2;
    }
    if (!chunk_near) continue;
    for (int ly = 0; ly < n; ++ly) {
      for (int lx = 0; lx < n; ++lx) {
        const GaussianMixture1D& g = chunk->mixture(lx, ly);
        if (g.empty()) continue;
        const Eigen::Vector2d xy = geometry.cellCenter({o.x + lx, o.y + ly});
        if (!near(xy)) continue;
        int best = 0;
        for (int j = 1; j < g.size(); ++j) {
          const GaussianComponent& a = g.component(j);
          const GaussianComponent& b = g.component(best);
          if (a.weight > b.weight || (a.weight == b.weight && a.mean_m < b.mean_m)) best = j;
        }
        cloud.points.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                  g.component(best).mean_m);
        cloud.intensity.push_back(static_cast<float>(g.size()));
        sigma_m.push_back(g.component(best).sigma_m);
      }
    }
  }
}

}  // namespace node
}  // namespace gmm_localization
