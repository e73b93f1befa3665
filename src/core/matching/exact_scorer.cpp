#include "gmm_localization/core/matching/exact_scorer.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {

namespace {
RasterWindow windowAround(const ChunkMap& map, double x, double y, double r) {
  const CellIndex lo = map.geometry().cellAt(x - r, y - r);
  const CellIndex hi = map.geometry().cellAt(x + r, y + r);
  return RasterWindow(map, lo.x, lo.y, hi.x, hi.y);
}
}  // namespace

ExactScorer::ExactScorer(const ChunkMap& map, double ll_floor, double center_x_m, double center_y_m,
                         double radius_m, double kernel_sigma_m)
    : map_(map),
      floor_(ll_floor),
      window_(windowAround(map, center_x_m, center_y_m, radius_m)),
      row_cells_(int64_t{1} << map.options().chunk_shift) {
  // Kernel width in cell units; at most a cell so the 3 x 3 neighbourhood holds the kernel.
  const double s = std::clamp(kernel_sigma_m / map.geometry().resolution_m, 0.05, 1.0);
  const double inv_two_s2 = 1.0 / (2.0 * s * s);
  kernel_table_.resize(kKernelTableSize);
  for (int i = 0; i < kKernelTableSize; ++i) {
    const double d = i / kKernelTableScale;
    kernel_table_[i] = std::exp(-d * d * inv_two_s2);
  }
}

double ExactScorer::floored(const CellIndex& c, double z) const {
  const MapChunk* chunk = window_.chunk(c.x, c.y);
  if (chunk == nullptr || !chunk->hasMixtures()) return floor_;
  const int mask = chunk->cells() - 1;
  const MixtureLogTerms& g =
      chunk->logTerms(static_cast<int>(c.x & mask), static_cast<int>(c.y & mask));
  return g.flooredLogLikelihood(z, floor_);
}

double ExactScorer::cellLogLikelihood(const Eigen::Vector3d& p) const {
  return floored(map_.geometry().cellAt(p.x(), p.y()), p.z());
}

namespace {
/// The cell of map-frame (x, y) and the offset from its centre, in cells.
struct CellOffset {
  int64_t cx, cy;
  double fx, fy;
};
CellOffset cellOffset(const MapGeometry& g, double x, double y) {
  const double u = (x - g.origin_x_m) / g.resolution_m;
  const double v = (y - g.origin_y_m) / g.resolution_m;
  const double fu = std::floor(u), fv = std::floor(v);
  return {static_cast<int64_t>(fu), static_cast<int64_t>(fv), u - fu - 0.5, v - fv - 0.5};
}
}  // namespace

double ExactScorer::pointLogLikelihood(const Eigen::Vector3d& p) const {
  // Gaussian-weighted mean of the floored log-likelihoods of the 3 x 3 cells around the point,
  // weights exp(-d^2 / (2 s^2)) of the distance d from the point to each cell centre: smooth in
  // x, y, and unbiased for structure between cell centres (a bilinear interpolation peaks at
  // cell centres and pulls walls onto them). The weights are separable: w = wx * wy.
  const CellOffset c = cellOffset(map_.geometry(), p.x(), p.y());
  double ll[9];
  blockLogLikelihoods(c.cx, c.cy, p.z(), ll);
  return weightedMean(c.fx, c.fy, ll);
}

const MixtureLogTerms* ExactScorer::blockFirst(int64_t cx, int64_t cy) const {
  const MapChunk* chunk = window_.chunk(cx, cy);
  if (chunk == nullptr || !chunk->hasMixtures() || chunk->cells() != row_cells_) return nullptr;
  const int64_t mask = chunk->cells() - 1;
  const int64_t lx = cx & mask, ly = cy & mask;
  if (lx < 1 || ly < 1 || lx + 1 > mask || ly + 1 > mask) return nullptr;
  return &chunk->logTerms(static_cast<int>(lx - 1), static_cast<int>(ly - 1));
}

void ExactScorer::blockLogLikelihoods(int64_t cx, int64_t cy, double z, double ll[9]) const {
  const MixtureLogTerms* first = blockFirst(cx, cy);
  if (first != nullptr) {
    blockLogLikelihoods(first, z, ll);  // the whole 3 x 3 block lies in one chunk
  } else {
    for (int ky = 0; ky < 3; ++ky) {
      for (int kx = 0; kx < 3; ++kx) ll[ky * 3 + kx] = floored({cx + kx - 1, cy + ky - 1}, z);
    }
  }
}

void ExactScorer::blockLogLikelihoods(const MixtureLogTerms* first, double z, double ll[9]) const {
  for (int ky = 0; ky < 3; ++ky) {
    const MixtureLogTerms* row = first + ky * row_cells_;
    for (int kx = 0; kx < 3; ++kx) ll[ky * 3 + kx] = row[kx].flooredLogLikelihood(z, floor_);
  }
}

double ExactScorer::weightedMean(double fx, double fy, const double ll[9]) const {
  double wx[3], wy[3];
  for (int k = 0; k < 3; ++k) {
    wx[k] = kernel(fx - (k - 1));
    wy[k] = kernel(fy - (k - 1));
  }
  double acc = 0.0, wsum = 0.0;
  for (int ky = 0; ky < 3; ++ky) {
    for (int kx = 0; kx < 3; ++kx) {
      const double w = wx[kx] * wy[ky];
      acc += w * ll[ky * 3 + kx];
      wsum += w;
    }
  }
  return acc / wsum;
}

double ExactScorer::kernel(double d) const {
  // exp(-d^2 / (2 s^2)) for |d| <= 1.5 cells, from a table with linear interpolation.
  const double x = std::min(std::abs(d), 1.5) * kKernelTableScale;
  const int i = std::min(static_cast<int>(x), kKernelTableSize - 2);
  const double a = x - i;
  return kernel_table_[i] + a * (kernel_table_[i + 1] - kernel_table_[i]);
}

template <typename PointValue, typename BlockStart>
double ExactScorer::blockSums(size_t points, TaskPool* pool, const PointValue& value,
                              const BlockStart& block_start) const {
  const size_t blocks = (points + kBlockPoints - 1) / kBlockPoints;
  auto block_sum = [&](size_t b) {
    double sum = 0.0;
    const size_t end = std::min(points, (b + 1) * kBlockPoints);
    block_start(b * kBlockPoints, end);
    for (size_t i = b * kBlockPoints; i < end; ++i) sum += value(i);
    return sum;
  };
  double partial[16];
  std::vector<double> many;
  double* sums = partial;
  if (blocks > 16) {
    many.resize(blocks);
    sums = many.data();
  }
  parallelFor(blocks > 1 ? pool : nullptr, static_cast<int>(blocks),
              [&](int b) { sums[b] = block_sum(static_cast<size_t>(b)); });
  double total = 0.0;
  for (size_t b = 0; b < blocks; ++b) total += sums[b];
  return total;
}

double ExactScorer::score(const PointList& base_points, const Pose6& pose, TaskPool* pool) const {
  const Eigen::Isometry3d T = toIsometry(pose);
  return blockSums(
      base_points.size(), pool,
      [&](size_t i) { return pointLogLikelihood(T * base_points[i].cast<double>()); },
      [](size_t, size_t) {});
}

double ExactScorer::scoreReusing(const PointList& base_points, const Pose6& pose,
                                 const std::vector<CellBlockMemo>* reuse,
                                 std::vector<CellBlockMemo>* out, TaskPool* pool,
                                 const std::vector<CellBlockMemo>* reuse_also) const {
  Pose6 tilt;
  tilt.roll = pose.roll;
  tilt.pitch = pose.pitch;
  const Eigen::Matrix3d R_tilt = toIsometry(tilt).linear();
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  auto usable = [&](const std::vector<CellBlockMemo>* m) {
    return m != nullptr && m->size() == base_points.size() ? m : nullptr;
  };
  const std::vector<CellBlockMemo>* sources[2] = {usable(reuse), usable(reuse_also)};
  out->resize(base_points.size());
  const MapGeometry& g = map_.geometry();
  // Each block of points in two passes: first every point's cell block and height, then the
  // values, summed in point order as score() does. The second pass requests the cells of the
  // point kAhead places on before it evaluates one: a point's nine cells are three rows of a
  // chunk far from the previous point's, and read one by one each would wait for memory.
  constexpr size_t kAhead = 8;
  std::vector<Eigen::Vector2d> offset(base_points.size());
  std::vector<uint8_t> evaluate(base_points.size());
  std::vector<const MixtureLogTerms*> first(base_points.size());  // blockFirst() when evaluated
  auto ask = [&](size_t i) {
    if (first[i] == nullptr) return;
    for (int ky = 0; ky < 3; ++ky) {
      const MixtureLogTerms* row = first[i] + ky * row_cells_;
      __builtin_prefetch(row);
      __builtin_prefetch(reinterpret_cast<const char*>(row + 3) - 1);
    }
  };
  auto place = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d q = R_tilt * base_points[i].cast<double>();
      const double z = q.z() + pose.z;
      const CellOffset o =
          cellOffset(g, c * q.x() - s * q.y() + pose.x, s * q.x() + c * q.y() + pose.y);
      offset[i] = {o.fx, o.fy};
      CellBlockMemo& m = (*out)[i];
      const CellBlockMemo* same = nullptr;
      for (const std::vector<CellBlockMemo>* from : sources) {
        if (same == nullptr && from != nullptr && (*from)[i].cx == o.cx && (*from)[i].cy == o.cy &&
            (*from)[i].z == z) {
          same = &(*from)[i];
        }
      }
      if (same != nullptr) {
        m = *same;
        evaluate[i] = 0;
        first[i] = nullptr;
      } else {
        m.cx = o.cx;
        m.cy = o.cy;
        m.z = z;
        evaluate[i] = 1;
        first[i] = blockFirst(o.cx, o.cy);
      }
    }
    for (size_t i = begin; i < std::min(end, begin + kAhead); ++i) ask(i);
  };
  return blockSums(
      base_points.size(), pool,
      [&](size_t i) {
        const size_t block_end =
            std::min(base_points.size(), (i / kBlockPoints + 1) * kBlockPoints);
        if (i + kAhead < block_end) ask(i + kAhead);
        CellBlockMemo& m = (*out)[i];
        if (first[i] != nullptr) {
          blockLogLikelihoods(first[i], m.z, m.ll);
        } else if (evaluate[i]) {
          blockLogLikelihoods(m.cx, m.cy, m.z, m.ll);  // a block across a chunk's edge
        }
        return weightedMean(offset[i].x(), offset[i].y(), m.ll);
      },
      place);
}

}  // namespace gmm_localization
