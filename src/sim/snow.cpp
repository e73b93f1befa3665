#include "gmm_localization/sim/snow.h"

#include <algorithm>
#include <cmath>

#include "gmm_localization/sim/random.h"
#include "town_blocks.h"

namespace gmm_localization {
namespace sim {

SnowCover::SnowCover(const PassConfig& config)
    : min_(config.snow_depth_min_m), max_(config.snow_depth_max_m) {
  Rng rng(hashKeys(config.seed, 0x5E0Full));
  for (double& p : phase_) p = rng.uniform(0.0, 2.0 * M_PI);
}

double SnowCover::depth(double x, double y) const {
  // Drifts at 30-60 m, ripples at 10 m: a smooth field in [-1, 1].
  const double v = 0.5 * std::sin(0.21 * x + phase_[0]) * std::cos(0.17 * y + phase_[1]) +
                   0.3 * std::sin(0.055 * x + 0.043 * y + phase_[2]) +
                   0.2 * std::sin(0.6 * x + phase_[3]) * std::sin(0.53 * y + phase_[4]);
  return min_ + (max_ - min_) * 0.5 * (v + 1.0);
}

TriangleMesh buildSnowbanks(const Town& town, const PassConfig& config, const SnowCover& cover) {
  TriangleMesh mesh;
  const double hmax = config.snowbank_max_height_m;
  if (hmax <= 0.0 || config.snowbank_coverage <= 0.0) return mesh;
  const double curb = town.config().curb_height_m;
  const double tau = std::cos(M_PI * std::min(0.999, config.snowbank_coverage));
  Rng rng(hashKeys(config.seed, 0xBA4Cull));
  for (const Block& b : townBlocks(town)) {
    for (int side = 0; side < 4; ++side) {
      if (!b.faces[side]) continue;
      Eigen::Vector2d p0, p1, out;  // curb line, and the direction into the road
      switch (side) {
        case 0:
          p0 = {b.x0, b.y0};
          p1 = {b.x0, b.y1};
          out = {-1, 0};
          break;
        case 1:
          p0 = {b.x1, b.y0};
          p1 = {b.x1, b.y1};
          out = {1, 0};
          break;
        case 2:
          p0 = {b.x0, b.y0};
          p1 = {b.x1, b.y0};
          out = {0, -1};
          break;
        default:
          p0 = {b.x0, b.y1};
          p1 = {b.x1, b.y1};
          out = {0, 1};
          break;
      }
      const double len = (p1 - p0).norm();
      const Eigen::Vector2d dir = (p1 - p0) / len;
      const double ph1 = rng.uniform(0.0, 2.0 * M_PI), ph2 = rng.uniform(0.0, 2.0 * M_PI);
      const int n = static_cast<int>(std::floor(len - 8.0));
      uint32_t prev = 0;
      bool have_prev = false;
      for (int k = 0; k <= n; ++k) {
        const double u = 4.0 + k;
        const double m = 0.65 * std::sin(2.0 * M_PI * u / 37.0 + ph1) +
                         0.35 * std::sin(2.0 * M_PI * u / 11.0 + ph2);
        const double r = std::clamp((m - tau) / 0.4, 0.0, 1.0);
        const double h = hmax * r * r * (3.0 - 2.0 * r);
        if (h < 0.03) {
          have_prev = false;
          continue;
        }
        const double w = 0.6 + 1.0 * h / hmax;
        const Eigen::Vector2d c = p0 + dir * u;
        const Eigen::Vector2d a = c - out * 0.4, pk = c + out * (0.3 * w), e = c + out * w;
        const uint32_t first = static_cast<uint32_t>(mesh.numVertices());
        mesh.addVertex(
            {a.x(), a.y(),
             town.terrainHeight(a.x(), a.y()) + curb + cover.depth(a.x(), a.y()) + 0.3 * h});
        mesh.addVertex(
            {pk.x(), pk.y(), town.terrainHeight(pk.x(), pk.y()) + cover.depth(pk.x(), pk.y()) + h});
        mesh.addVertex(
            {e.x(), e.y(), town.terrainHeight(e.x(), e.y()) + cover.depth(e.x(), e.y())});
        if (have_prev) {
          for (uint32_t j = 0; j < 2; ++j) {
            mesh.addTriangle(prev + j, first + j, first + j + 1, Material::kSnow, kLabelSnow);
            mesh.addTriangle(prev + j, first + j + 1, prev + j + 1, Material::kSnow, kLabelSnow);
          }
        }
        prev = first;
        have_prev = true;
      }
    }
  }
  return mesh;
}

}  // namespace sim
}  // namespace gmm_localization
