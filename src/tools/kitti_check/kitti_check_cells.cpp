#include "kitti_check/kitti_check_cells.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "bench/bench_data.h"

namespace gmm_localization {
namespace kitti_check {

namespace {

using bench::median;
using bench::percentile;

struct Key3Hash {
  size_t operator()(const Eigen::Vector3i& k) const {
    return (static_cast<size_t>(k.x()) * 73856093u) ^ (static_cast<size_t>(k.y()) * 19349663u) ^
           (static_cast<size_t>(k.z()) * 83492791u);
  }
};
struct Key3Eq {
  bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
};

// (Shifted as unsigned: a left shift of a negative value is undefined.)
int64_t key2(int64_t x, int64_t y) {
  return static_cast<int64_t>(static_cast<uint64_t>(x) << 32) ^ (y & 0xffffffffLL);
}

/// Lowest height of a square with at least min(kSupport, n) of its points within band_m above
/// it: isolated returns below the ground (reflection ghosts) do not pull the level down.
float supportedLow(std::vector<float>& z, double band_m) {
  constexpr size_t kSupport = 5;
  std::sort(z.begin(), z.end());
  const size_t need = std::min(kSupport, z.size());
  size_t hi = 0;
  for (size_t lo = 0; lo < z.size(); ++lo) {
    hi = std::max(hi, lo);
    while (hi + 1 < z.size() && z[hi + 1] <= z[lo] + band_m) ++hi;
    if (hi - lo + 1 >= need) return z[lo];
  }
  return z.front();
}

/// Ground level per point (see the header).
std::vector<float> groundLevels(const PointList& pts, double cell_m, double band_m) {
  auto sq = [&](const Eigen::Vector3f& p) {
    return key2(static_cast<int64_t>(std::floor(p.x() / cell_m)),
                static_cast<int64_t>(std::floor(p.y() / cell_m)));
  };
  std::unordered_map<int64_t, std::vector<float>> heights;
  std::unordered_map<int64_t, Eigen::Vector2d> centre;
  for (const Eigen::Vector3f& p : pts) {
    heights[sq(p)].push_back(p.z());
    centre[sq(p)] = Eigen::Vector2d((std::floor(p.x() / cell_m) + 0.5) * cell_m,
                                    (std::floor(p.y() / cell_m) + 0.5) * cell_m);
  }
  std::unordered_map<int64_t, float> low;
  for (auto& [k, z] : heights) low.emplace(k, supportedLow(z, band_m));
  // Robust plane through the squares' levels: start level at their median, then refit on the
  // squares within 1.0, 0.5 and 0.3 m of the current plane.
  std::vector<double> lows;
  for (const auto& [k, z] : low) lows.push_back(z);
  Eigen::Vector3d plane(0.0, 0.0, median(lows));  // z = a x + b y + c
  for (double keep : {1.0, 0.5, 0.3}) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (const auto& [k, z] : low) {
      const Eigen::Vector3d row(centre.at(k).x(), centre.at(k).y(), 1.0);
      if (std::abs(row.dot(plane) - z) > keep) continue;
      ata += row * row.transpose();
      atb += row * z;
    }
    if (std::abs(ata.determinant()) > 1e-9) plane = ata.ldlt().solve(atb);
  }
  std::vector<float> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const int64_t k = sq(pts[i]);
    const Eigen::Vector3d row(centre.at(k).x(), centre.at(k).y(), 1.0);
    const double ref = row.dot(plane);
    const float own = low.at(k);
    out[i] = std::abs(own - ref) <= 0.5 ? own : static_cast<float>(ref);
  }
  return out;
}

}  // namespace

const char* className(PointClass c) {
  switch (c) {
    case PointClass::kGround:
      return "ground";
    case PointClass::kWall:
      return "wall";
    case PointClass::kVegetation:
      return "vegetation";
    case PointClass::kBelowGround:
      return "below ground";
    case PointClass::kOther:
      break;
  }
  return "other";
}

int CellRecord::points() const {
  int n = 0;
  for (int c : points_by_class) n += c;
  return n;
}

PointLabels classifyPoints(const PointList& pts, const ClassifierOptions& o) {
  PointLabels out;
  out.ground_z = groundLevels(pts, o.ground_cell_m, o.ground_band_m);
  out.labels.assign(pts.size(), PointClass::kGround);
  const double r = o.neighbour_radius_m;
  std::unordered_map<Eigen::Vector3i, std::vector<uint32_t>, Key3Hash, Key3Eq> grid;
  auto key = [&](const Eigen::Vector3f& p) {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / r)),
                           static_cast<int>(std::floor(p.y() / r)),
                           static_cast<int>(std::floor(p.z() / r)));
  };
  for (size_t i = 0; i < pts.size(); ++i) grid[key(pts[i])].push_back(static_cast<uint32_t>(i));
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f& p = pts[i];
    if (p.z() < out.ground_z[i] - o.below_ground_m) {
      out.labels[i] = PointClass::kBelowGround;
      continue;
    }
    if (p.z() <= out.ground_z[i] + o.ground_band_m) continue;  // ground
    // Neighbours within r: the 27 grid cells around.
    const Eigen::Vector3i k = key(p);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
    int n = 0;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = grid.find(k + Eigen::Vector3i(dx, dy, dz));
          if (it == grid.end()) continue;
          for (uint32_t j : it->second) {
            const Eigen::Vector3d d = (pts[j] - p).cast<double>();
            if (d.squaredNorm() > r * r) continue;
            sum += d;
            sq += d * d.transpose();
            ++n;
          }
        }
      }
    }
    if (n < o.min_neighbours) {
      out.labels[i] = PointClass::kOther;
      continue;
    }
    const Eigen::Vector3d mean = sum / n;
    const Eigen::Matrix3d cov = sq / n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    // Ascending eigenvalues: s3 <= s2 <= s1 as standard deviations.
    const double s3 = std::sqrt(std::max(0.0, es.eigenvalues()(0)));
    const double s2 = std::sqrt(std::max(0.0, es.eigenvalues()(1)));
    const double s1 = std::sqrt(std::max(1e-12, es.eigenvalues()(2)));
    const double a1 = (s1 - s2) / s1, a2 = (s2 - s3) / s1, a3 = s3 / s1;
    const double nz = std::abs(es.eigenvectors().col(0).z());
    if (a3 >= a1 && a3 >= a2) {
      out.labels[i] = PointClass::kVegetation;
    } else if (a2 >= a1 && nz <= o.wall_max_normal_z) {
      out.labels[i] = PointClass::kWall;
    } else {
      out.labels[i] = PointClass::kOther;
    }
  }
  return out;
}

std::vector<CellRecord> classifyCells(const GmmMap& map, const PointList& pts,
                                      const PointLabels& labels) {
  const MapGeometry& g = map.geometry();
  std::unordered_map<int64_t, size_t> index;
  std::vector<CellRecord> cells;
  for (size_t i = 0; i < pts.size(); ++i) {
    const CellIndex c = g.cellAt(pts[i].x(), pts[i].y());
    auto it = index.find(key2(c.x, c.y));
    if (it == index.end()) {
      CellRecord r;
      r.cell = c;
      r.centre = g.cellCenter(c);
      const GaussianMixture1D* m = map.cell(c);
      if (m != nullptr) r.mixture = *m;
      r.ground_z = labels.ground_z[i];
      it = index.emplace(key2(c.x, c.y), cells.size()).first;
      cells.push_back(std::move(r));
    }
    CellRecord& r = cells[it->second];
    ++r.points_by_class[static_cast<int>(labels.labels[i])];
    r.z.push_back(pts[i].z());
    r.ground_z = std::min(r.ground_z, labels.ground_z[i]);
  }
  std::vector<CellRecord> out;
  for (CellRecord& r : cells) {
    if (r.mixture.empty()) continue;
    const auto& n = r.points_by_class;
    if (n[1] + n[2] + n[3] + n[4] == 0) {
      r.cls = PointClass::kGround;
    } else {
      int best = 1;
      for (int c = 2; c < kPointClasses; ++c) {
        if (n[c] > n[best]) best = c;
      }
      r.cls = static_cast<PointClass>(best);
    }
    std::sort(r.z.begin(), r.z.end());
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        auto n = index.find(key2(r.cell.x + dx, r.cell.y + dy));
        if ((dx == 0 && dy == 0) || n == index.end()) continue;
        const std::vector<float>& z = cells[n->second].z;
        r.neighbour_z.insert(r.neighbour_z.end(), z.begin(), z.end());
      }
    }
    std::sort(r.neighbour_z.begin(), r.neighbour_z.end());
    out.push_back(r);
  }
  std::sort(out.begin(), out.end(), [](const CellRecord& a, const CellRecord& b) {
    return a.cell.y < b.cell.y || (a.cell.y == b.cell.y && a.cell.x < b.cell.x);
  });
  return out;
}

namespace {
/// Typical shape of a cell's mixture: sigma for K = 1, distance between the means for K = 2.
double shapeOf(const GaussianMixture1D& g) {
  if (g.size() == 1) return g.component(0).sigma_m;
  return std::abs(g.component(1).mean_m - g.component(0).mean_m);
}
}  // namespace

std::vector<size_t> exampleCells(const std::vector<CellRecord>& cells,
                                 const std::vector<Eigen::Vector2d>& centres, double radius_m) {
  auto inside = [&](const CellRecord& r) {
    if (centres.empty()) return true;
    for (const Eigen::Vector2d& c : centres) {
      if ((r.centre - c).norm() <= radius_m) return true;
    }
    return false;
  };
  std::vector<size_t> out;
  for (int c = 0; c < kPointClasses; ++c) {
    for (int k = 1; k <= 2; ++k) {
      std::vector<size_t> group;
      std::vector<double> npts, shape;
      for (size_t i = 0; i < cells.size(); ++i) {
        if (static_cast<int>(cells[i].cls) != c || cells[i].mixture.size() != k) continue;
        if (!inside(cells[i])) continue;
        group.push_back(i);
        npts.push_back(cells[i].points());
        shape.push_back(shapeOf(cells[i].mixture));
      }
      if (group.empty()) continue;
      // Well observed (points in the group's top decile) and typical (shape nearest the
      // group's median).
      const double min_points = percentile(npts, 90);
      const double typical = median(shape);
      long best = -1;
      for (size_t i : group) {
        if (cells[i].points() < min_points) continue;
        const double d = std::abs(shapeOf(cells[i].mixture) - typical);
        if (best < 0 || d < std::abs(shapeOf(cells[best].mixture) - typical)) {
          best = static_cast<long>(i);
        }
      }
      if (best >= 0) out.push_back(static_cast<size_t>(best));
    }
  }
  return out;
}

}  // namespace kitti_check
}  // namespace gmm_localization
