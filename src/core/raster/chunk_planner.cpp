#include "gmm_localization/core/raster/chunk_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "gmm_localization/core/raster/chunk_reach.h"

namespace gmm_localization {
namespace {

/// Distance from p to the axis-aligned square [lo, lo + edge)^2 [m].
double distanceToSquare(const Eigen::Vector2d& lo, double edge, const PlanCentre& p) {
  const double dx = std::max({lo.x() - p.x(), 0.0, p.x() - (lo.x() + edge)});
  const double dy = std::max({lo.y() - p.y(), 0.0, p.y() - (lo.y() + edge)});
  return std::hypot(dx, dy);
}

bool finite(const PlanCentre& p) { return std::isfinite(p.x()) && std::isfinite(p.y()); }

}  // namespace

ChunkPlanner::ChunkPlanner(const MapGeometry& geometry, const RasterOptions& raster,
                           const std::vector<TileId>& tiles_present)
    : geometry_(geometry), raster_(raster), tiles_(tiles_present.begin(), tiles_present.end()) {}

Eigen::Vector2d ChunkPlanner::chunkMin(ChunkId id) const {
  const double edge = chunkEdgeM();
  return {geometry_.origin_x_m + id.x * edge, geometry_.origin_y_m + id.y * edge};
}

double ChunkPlanner::distanceToChunk(ChunkId id, const PlanCentre& p) const {
  return distanceToSquare(chunkMin(id), chunkEdgeM(), p);
}

double ChunkPlanner::distanceToChunk(ChunkId id, const std::vector<PlanCentre>& centres) const {
  double d = std::numeric_limits<double>::infinity();
  for (const PlanCentre& c : centres) {
    if (finite(c)) d = std::min(d, distanceToChunk(id, c));
  }
  return d;
}

double ChunkPlanner::distanceToTile(TileId id, const PlanCentre& p) const {
  const double edge = geometry_.tileSizeM();
  const Eigen::Vector2d lo(geometry_.origin_x_m + id.x * edge, geometry_.origin_y_m + id.y * edge);
  return distanceToSquare(lo, edge, p);
}

double ChunkPlanner::distanceToTile(TileId id, const std::vector<PlanCentre>& centres) const {
  double d = std::numeric_limits<double>::infinity();
  for (const PlanCentre& c : centres) {
    if (finite(c)) d = std::min(d, distanceToTile(id, c));
  }
  return d;
}

std::vector<TileId> ChunkPlanner::tilesFor(ChunkId id) const {
  std::vector<TileId> out;
  for (const TileId& t : chunkReadTiles(geometry_, id, raster_)) {
    if (tiles_.count(t) > 0) out.push_back(t);
  }
  return out;
}

std::vector<ChunkId> ChunkPlanner::needed(const std::vector<PlanCentre>& centres,
                                          double radius_m) const {
  std::vector<ChunkId> out;
  if (!(radius_m >= 0.0) || tiles_.empty()) return out;
  const double edge = chunkEdgeM();
  std::unordered_set<ChunkId, ChunkIdHash> seen;
  for (const PlanCentre& c : centres) {
    if (!finite(c)) continue;
    const auto lo_x =
        static_cast<int64_t>(std::floor((c.x() - radius_m - geometry_.origin_x_m) / edge));
    const auto hi_x =
        static_cast<int64_t>(std::floor((c.x() + radius_m - geometry_.origin_x_m) / edge));
    const auto lo_y =
        static_cast<int64_t>(std::floor((c.y() - radius_m - geometry_.origin_y_m) / edge));
    const auto hi_y =
        static_cast<int64_t>(std::floor((c.y() + radius_m - geometry_.origin_y_m) / edge));
    // Chunk ids are int32: a centre that far from the origin has no map anyway.
    constexpr int64_t kLimit = std::numeric_limits<int32_t>::max() / 2;
    if (std::abs(lo_x) > kLimit || std::abs(hi_x) > kLimit || std::abs(lo_y) > kLimit ||
        std::abs(hi_y) > kLimit) {
      continue;
    }
    for (int64_t x = lo_x; x <= hi_x; ++x) {
      for (int64_t y = lo_y; y <= hi_y; ++y) {
        const ChunkId id{static_cast<int32_t>(x), static_cast<int32_t>(y)};
        if (seen.count(id) > 0 || distanceToChunk(id, c) > radius_m) continue;
        seen.insert(id);
        if (hasData(id)) out.push_back(id);
      }
    }
  }
  // Nearest first by the distance from the closest centre to the chunk's centre.
  std::vector<std::pair<double, ChunkId>> keyed;
  keyed.reserve(out.size());
  for (const ChunkId& id : out) {
    const Eigen::Vector2d mid = chunkMin(id) + Eigen::Vector2d::Constant(edge / 2);
    double d = std::numeric_limits<double>::infinity();
    for (const PlanCentre& c : centres) {
      if (finite(c)) d = std::min(d, (mid - c).norm());
    }
    keyed.emplace_back(d, id);
  }
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first, a.second.x, a.second.y) < std::tie(b.first, b.second.x, b.second.y);
  });
  for (size_t i = 0; i < keyed.size(); ++i) out[i] = keyed[i].second;
  return out;
}

std::vector<ChunkId> ChunkPlanner::toEvict(const std::vector<ChunkId>& held,
                                           const std::vector<PlanCentre>& centres,
                                           double keep_radius_m) const {
  std::vector<ChunkId> out;
  for (const ChunkId& id : held) {
    if (!(distanceToChunk(id, centres) <= keep_radius_m)) out.push_back(id);
  }
  return out;
}

CentreSelection selectCentres(const PositionSources& s, double hint_hold_s) {
  CentreSelection out;
  if (s.tf) {
    out.centres.push_back(*s.tf);
    out.source = "tf";
    if (s.hint && s.hint_age_s < hint_hold_s) {
      out.centres.push_back(*s.hint);
      out.source = "tf+pose_hint";
    }
  } else if (s.hint && (!s.last_tf || s.hint_age_s <= s.last_tf_age_s)) {
    out.centres.push_back(*s.hint);
    out.source = "pose_hint";
  } else if (s.last_tf) {
    out.centres.push_back(*s.last_tf);
    out.source = "last_tf";
  } else if (s.initial) {
    out.centres.push_back(*s.initial);
    out.source = "initial";
  } else {
    out.source = "none";
  }
  return out;
}

}  // namespace gmm_localization
