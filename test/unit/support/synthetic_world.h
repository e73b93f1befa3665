#pragma once
// Test support: a small analytic street world (sloped ground, box buildings, poles), a map of
// it, and scans of it from any pose. Seeded and deterministic. The map stands in for the map
// builder: per cell, points sampled on the surfaces are blurred into the 3 x 3 neighbouring
// cells by a Gaussian kernel on their true x-y distance, then split into a ground and a
// structure cluster whose weighted moments give up to two components.

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"

namespace gmm_localization {
namespace testing {

struct Box {
  double x0, y0, x1, y1, height;
};
struct Pole {
  double x, y, radius, height;
};

class SyntheticWorld {
 public:
  /// Buildings along both sides of streets on a grid of pitch `block_m` over +-half_m.
  SyntheticWorld(uint32_t seed, double half_m = 60.0, double block_m = 40.0) : half_(half_m) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (double bx = -half_m; bx < half_m; bx += block_m) {
      for (double by = -half_m; by < half_m; by += block_m) {
        // A block: street of 12 m on its low edges, buildings of random footprints inside.
        const double x0 = bx + 6.0, y0 = by + 6.0, x1 = bx + block_m - 6.0;
        double x = x0;
        while (x < x1 - 3.0) {
          const double w = 5.0 + 10.0 * u(rng);
          const double setback = 2.0 * u(rng);
          boxes_.push_back({x, y0 + setback, std::min(x + w, x1), y0 + setback + 6.0 + 8.0 * u(rng),
                            4.0 + 14.0 * u(rng)});
          x += w + 1.0 + 3.0 * u(rng);
        }
        for (int k = 0; k < 3; ++k) {
          poles_.push_back(
              {bx + 3.0 + 30.0 * u(rng), by + 3.5 + 0.5 * u(rng), 0.15, 5.0 + 3.0 * u(rng)});
        }
      }
    }
  }

  double ground(double x, double y) const { return 0.01 * x + 0.005 * y; }

  /// Surface samples (map frame) of everything within radius r of (cx, cy), spacing ~step.
  std::vector<Eigen::Vector3d> surfaceSamples(double cx, double cy, double r, double step,
                                              std::mt19937& rng) const {
    std::uniform_real_distribution<double> jitter(-0.5 * step, 0.5 * step);
    std::vector<Eigen::Vector3d> pts;
    for (double x = cx - r; x <= cx + r; x += step) {
      for (double y = cy - r; y <= cy + r; y += step) {
        const double px = x + jitter(rng), py = y + jitter(rng);
        if (insideBuilding(px, py)) continue;
        pts.emplace_back(px, py, ground(px, py));
      }
    }
    for (const Box& b : boxes_) {
      if (std::hypot(0.5 * (b.x0 + b.x1) - cx, 0.5 * (b.y0 + b.y1) - cy) > r + 20.0) continue;
      const double g = ground(b.x0, b.y0);
      for (double z = step; z < b.height; z += step) {
        for (double x = b.x0; x <= b.x1; x += step) {
          pts.emplace_back(x, b.y0, g + z);
          pts.emplace_back(x, b.y1, g + z);
        }
        for (double y = b.y0; y <= b.y1; y += step) {
          pts.emplace_back(b.x0, y, g + z);
          pts.emplace_back(b.x1, y, g + z);
        }
      }
    }
    for (const Pole& p : poles_) {
      if (std::hypot(p.x - cx, p.y - cy) > r + 2.0) continue;
      const double g = ground(p.x, p.y);
      for (double z = step; z < p.height; z += step) {
        for (int a = 0; a < 12; ++a) {
          pts.emplace_back(p.x + p.radius * std::cos(a * M_PI / 6),
                           p.y + p.radius * std::sin(a * M_PI / 6), g + z);
        }
      }
    }
    return pts;
  }

  /// A map over +-half of the world: cells of `geometry`, tiles covering the area.
  GmmMap buildMap(const MapGeometry& geometry, uint32_t seed) const {
    std::mt19937 rng(seed);
    const auto samples = surfaceSamples(0.0, 0.0, half_ + 10.0, 0.07, rng);
    struct Acc {
      double wg = 0, sg = 0, qg = 0, ws = 0, ss = 0, qs = 0;
    };
    const CellIndex lo = geometry.cellAt(-half_ - 12.0, -half_ - 12.0);
    const CellIndex hi = geometry.cellAt(half_ + 12.0, half_ + 12.0);
    const int64_t nx = hi.x - lo.x + 1, ny = hi.y - lo.y + 1;
    std::vector<Acc> acc(static_cast<size_t>(nx * ny));
    const double kernel_sigma = 0.1;
    for (const Eigen::Vector3d& p : samples) {
      const CellIndex c = geometry.cellAt(p.x(), p.y());
      const bool is_ground = p.z() < ground(p.x(), p.y()) + 0.25;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const CellIndex n{c.x + dx, c.y + dy};
          if (n.x < lo.x || n.y < lo.y || n.x > hi.x || n.y > hi.y) continue;
          const Eigen::Vector2d centre = geometry.cellCenter(n);
          const double d2 = (centre - p.head<2>()).squaredNorm();
          const double w = std::exp(-0.5 * d2 / (kernel_sigma * kernel_sigma));
          Acc& a = acc[static_cast<size_t>((n.y - lo.y) * nx + (n.x - lo.x))];
          if (is_ground) {
            a.wg += w, a.sg += w * p.z(), a.qg += w * p.z() * p.z();
          } else {
            a.ws += w, a.ss += w * p.z(), a.qs += w * p.z() * p.z();
          }
        }
      }
    }
    GmmMap map(geometry);
    const TileId t0 = geometry.tileOf(lo), t1 = geometry.tileOf(hi);
    for (int32_t ty = t0.y; ty <= t1.y; ++ty) {
      for (int32_t tx = t0.x; tx <= t1.x; ++tx) {
        auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, geometry.tile_size_cells);
        const CellIndex o = geometry.tileOrigin({tx, ty});
        for (int ly = 0; ly < geometry.tile_size_cells; ++ly) {
          for (int lx = 0; lx < geometry.tile_size_cells; ++lx) {
            const CellIndex c{o.x + lx, o.y + ly};
            if (c.x < lo.x || c.y < lo.y || c.x > hi.x || c.y > hi.y) continue;
            const Acc& a = acc[static_cast<size_t>((c.y - lo.y) * nx + (c.x - lo.x))];
            const double total = a.wg + a.ws;
            if (total < 0.5) continue;
            GaussianMixture1D& g = tile->at(lx, ly);
            auto add = [&](double w, double s, double q) {
              if (w < 0.05 * total) return;
              const double mean = s / w;
              const double var = std::max(q / w - mean * mean, 0.0);
              g.add({static_cast<float>(w / total), static_cast<float>(mean),
                     static_cast<float>(std::sqrt(var + 0.03 * 0.03))});
            };
            add(a.wg, a.sg, a.qg);
            add(a.ws, a.ss, a.qs);
            // Renormalise after dropping a small cluster.
            double wsum = 0.0;
            for (int j = 0; j < g.size(); ++j) wsum += g.component(j).weight;
            for (int j = 0; j < g.size(); ++j) g.component(j).weight /= static_cast<float>(wsum);
          }
        }
        map.insert(tile);
      }
    }
    return map;
  }

  /// A scan of the world from `pose` (base_link in map), in base_link, within max_range:
  /// surface samples at spacing `step`, optionally with Gaussian range-like noise [m].
  PointList scan(const Pose6& pose, double max_range, double step, double noise_m,
                 uint32_t seed) const {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    const auto samples = surfaceSamples(pose.x, pose.y, max_range, step, rng);
    const Eigen::Isometry3d T = Eigen::Translation3d(pose.x, pose.y, pose.z) *
                                Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(pose.pitch, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(pose.roll, Eigen::Vector3d::UnitX());
    const Eigen::Isometry3d Tinv = T.inverse();
    PointList out;
    for (const Eigen::Vector3d& p : samples) {
      if (std::hypot(p.x() - pose.x, p.y() - pose.y) > max_range) continue;
      Eigen::Vector3d q = Tinv * p;
      if (noise_m > 0.0) q += q.normalized() * noise_m * n(rng);
      out.push_back(q.cast<float>());
    }
    return out;
  }

  /// A pose on a street (ground height + 0 for base_link on the ground).
  Pose6 streetPose(std::mt19937& rng) const {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Pose6 p;
    // The streets run along the low x (and y) edge of each 40 m block starting at -60 m.
    const int i = static_cast<int>(u(rng) * 2.0);
    p.x = -20.0 + 40.0 * i + 2.5 + 1.0 * u(rng);  // a north-south street
    p.y = -20.0 + 40.0 * u(rng);
    if (u(rng) < 0.5) std::swap(p.x, p.y);
    p.z = ground(p.x, p.y);
    p.yaw = 2.0 * M_PI * u(rng) - M_PI;
    return p;
  }

  const std::vector<Box>& boxes() const { return boxes_; }

 private:
  bool insideBuilding(double x, double y) const {
    for (const Box& b : boxes_) {
      if (x > b.x0 && x < b.x1 && y > b.y0 && y < b.y1) return true;
    }
    return false;
  }

  double half_;
  std::vector<Box> boxes_;
  std::vector<Pole> poles_;
};

}  // namespace testing
}  // namespace gmm_localization
