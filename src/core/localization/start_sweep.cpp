#include "gmm_localization/core/localization/start_sweep.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {
namespace {

/// Centres along one axis: the first at lo + h, the last at hi - h, evenly spaced at most `step`
/// apart; one centre in the middle when the span is shorter than a window.
std::vector<double> axisCentres(double lo, double hi, double h, double step) {
  const double first = lo + h, last = hi - h;
  if (last <= first) return {0.5 * (lo + hi)};
  const int n = static_cast<int>(std::ceil((last - first) / step - 1e-9)) + 1;
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) out[i] = first + (last - first) * i / (n - 1);
  return out;
}

bool overlaps(const Eigen::AlignedBox2d& a, const Eigen::AlignedBox2d& b) {
  return a.min().x() < b.max().x() && b.min().x() < a.max().x() && a.min().y() < b.max().y() &&
         b.min().y() < a.max().y();
}

Eigen::AlignedBox2d square(const Eigen::Vector2d& centre, double half) {
  return {centre - Eigen::Vector2d::Constant(half), centre + Eigen::Vector2d::Constant(half)};
}

}  // namespace

std::string StartSweepOptions::validate() const {
  if (!(window_half_xy_m >= 1.0 && window_half_xy_m <= 1000.0)) {
    return "window_half_xy_m must be in [1, 1000] m";
  }
  if (!(overlap_m >= 0.0 && overlap_m < window_half_xy_m)) {
    return "overlap_m must be in [0, window_half_xy_m)";
  }
  if (!(wait_s >= 0.0 && wait_s <= 3600.0)) return "wait_s must be in [0, 3600] s";
  if (!(map_wait_s >= 0.0 && map_wait_s <= 600.0)) return "map_wait_s must be in [0, 600] s";
  if (!(attempt_timeout_s >= 1.0 && attempt_timeout_s <= 3600.0)) {
    return "attempt_timeout_s must be in [1, 3600] s";
  }
  if (max_sweeps < 0) return "max_sweeps must be >= 0 (0: no limit)";
  if (!std::isfinite(region_x_m) || !std::isfinite(region_y_m) ||
      !(region_radius_m >= 0.0 && region_radius_m <= 1e6)) {
    return "region_x_m, region_y_m must be finite and region_radius_m in [0, 1e6] m";
  }
  return {};
}

std::vector<Eigen::AlignedBox2d> tileSquares(const MapGeometry& geometry,
                                             const std::vector<TileId>& tiles) {
  std::vector<Eigen::AlignedBox2d> out;
  out.reserve(tiles.size());
  const double edge = geometry.tileSizeM();
  for (const TileId& t : tiles) {
    const Eigen::Vector2d lo(geometry.origin_x_m + t.x * edge, geometry.origin_y_m + t.y * edge);
    out.emplace_back(lo, lo + Eigen::Vector2d::Constant(edge));
  }
  return out;
}

std::vector<Eigen::Vector2d> sweepWindowCentres(const std::vector<Eigen::AlignedBox2d>& tiles,
                                                const StartSweepOptions& o) {
  const Eigen::Vector2d fix(o.region_x_m, o.region_y_m);
  std::vector<Eigen::AlignedBox2d> kept;
  for (const auto& t : tiles) {
    if (t.isEmpty()) continue;
    if (o.hasRegion() && t.exteriorDistance(fix) > o.region_radius_m) continue;
    kept.push_back(t);
  }
  if (kept.empty()) return {};
  Eigen::AlignedBox2d box;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& t : kept) {
    box.extend(t);
    centroid += t.center();
  }
  centroid /= static_cast<double>(kept.size());
  const Eigen::Vector2d from = o.hasRegion() ? fix : centroid;
  if (o.hasRegion()) {  // only the part of the tiles within the disc needs covering
    box = box.intersection(square(fix, o.region_radius_m));
  }
  const double h = o.window_half_xy_m, m = 0.5 * o.overlap_m;
  const double step = 2.0 * (h - m);
  const auto xs = axisCentres(box.min().x() - m, box.max().x() + m, h, step);
  const auto ys = axisCentres(box.min().y() - m, box.max().y() + m, h, step);
  std::vector<Eigen::Vector2d> out;
  for (double y : ys) {
    for (double x : xs) {
      const Eigen::Vector2d c(x, y);
      const auto w = square(c, h);
      const bool any =
          std::any_of(kept.begin(), kept.end(), [&](const auto& t) { return overlaps(w, t); });
      if (any) out.push_back(c);
    }
  }
  std::stable_sort(out.begin(), out.end(), [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - from).squaredNorm() < (b - from).squaredNorm();
  });
  return out;
}

std::vector<ChunkId> windowChunks(const ChunkPlanner& planner, const Eigen::Vector2d& centre,
                                  double half_xy_m) {
  const double edge = planner.chunkEdgeM();
  const MapGeometry& g = planner.geometry();
  const auto w = square(centre, half_xy_m);
  const auto index = [&](double v, double origin) {
    return static_cast<int32_t>(std::floor((v - origin) / edge));
  };
  std::vector<ChunkId> out;
  for (int32_t cx = index(w.min().x(), g.origin_x_m); cx <= index(w.max().x(), g.origin_x_m);
       ++cx) {
    for (int32_t cy = index(w.min().y(), g.origin_y_m); cy <= index(w.max().y(), g.origin_y_m);
         ++cy) {
      const ChunkId id{cx, cy};
      const Eigen::Vector2d lo = planner.chunkMin(id);
      if (!overlaps(w, {lo, lo + Eigen::Vector2d::Constant(edge)})) continue;
      if (planner.hasData(id)) out.push_back(id);
    }
  }
  return out;
}

const char* StartSweep::stateName(State s) {
  switch (s) {
    case State::kWaiting:
      return "waiting";
    case State::kLoading:
      return "loading";
    case State::kSearching:
      return "searching";
    case State::kLocalized:
      return "localized";
    case State::kStoodDown:
      return "stood_down";
    case State::kGaveUp:
      return "gave_up";
  }
  return "?";
}

StartSweep::StartSweep(StartSweepOptions options) : options_(options) {}

void StartSweep::setWindows(std::vector<Eigen::Vector2d> centres) {
  windows_ = std::move(centres);
  if (state_ == State::kLoading || state_ == State::kSearching) state_ = State::kWaiting;
  index_ = -1;
  sweeps_ = 0;
  no_prior_since_s_ = -1.0;
}

void StartSweep::onStatus(double now_s, const Answer& a) {
  if (state_ == State::kLocalized || state_ == State::kStoodDown || state_ == State::kGaveUp) {
    return;
  }
  if (a.accepted) {
    state_ = State::kLocalized;
    return;
  }
  if (state_ == State::kWaiting) {
    if (!a.no_prior) {
      no_prior_since_s_ = -1.0;
    } else if (no_prior_since_s_ < 0.0) {
      no_prior_since_s_ = now_s;
    }
  } else if (state_ == State::kSearching && a.global_search &&
             (a.window_centre - windows_[index_]).norm() <= 0.25 * options_.window_half_xy_m) {
    answered_ = true;
  }
}

void StartSweep::onExternalPose() {
  if (state_ == State::kWaiting || state_ == State::kLoading || state_ == State::kSearching) {
    state_ = State::kStoodDown;
  }
}

StartSweep::Action StartSweep::enter(State state, Action::Kind kind, double now_s) {
  state_ = state;
  phase_since_s_ = now_s;
  Action a;
  a.kind = kind;
  a.window = index_;
  a.centre = windows_[index_];
  return a;
}

StartSweep::Action StartSweep::poll(double now_s, bool map_loaded) {
  switch (state_) {
    case State::kWaiting:
      if (windows_.empty() || no_prior_since_s_ < 0.0 ||
          now_s - no_prior_since_s_ < options_.wait_s) {
        return {};
      }
      index_ = 0;
      return enter(State::kLoading, Action::Kind::kLoadMap, now_s);
    case State::kLoading: {
      if (!map_loaded && now_s - phase_since_s_ < options_.map_wait_s) return {};
      if (!map_loaded) ++early_;
      ++searched_;
      answered_ = false;
      return enter(State::kSearching, Action::Kind::kSearch, now_s);
    }
    case State::kSearching: {
      const bool timed_out = now_s - phase_since_s_ >= options_.attempt_timeout_s;
      if (!answered_ && !timed_out) return {};
      if (!answered_) ++timed_out_;
      if (++index_ == static_cast<int>(windows_.size())) {
        index_ = 0;
        ++sweeps_;
        if (options_.max_sweeps > 0 && sweeps_ >= options_.max_sweeps) {
          state_ = State::kGaveUp;
          return {};
        }
      }
      return enter(State::kLoading, Action::Kind::kLoadMap, now_s);
    }
    default:
      return {};
  }
}

}  // namespace gmm_localization
