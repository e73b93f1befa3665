// Town: configuration checks and the analytic ground surface (terrain, crowned roads, curbs,
// painted markings). Layout generation is in town_layout.cpp.
#include "gmm_localization/sim/town.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gmm_localization {
namespace sim {
namespace {

Status rangeError(const char* key, double value, const char* allowed) {
  std::ostringstream os;
  os << "TownConfig." << key << " = " << value << " is outside " << allowed;
  return Status::failure(os.str());
}

}  // namespace

Status TownConfig::validate() const {
  if (!(size_x_m >= 100.0 && size_x_m <= 10000.0))
    return rangeError("size_x_m", size_x_m, "[100, 10000]");
  if (!(size_y_m >= 100.0 && size_y_m <= 10000.0))
    return rangeError("size_y_m", size_y_m, "[100, 10000]");
  if (!(block_min_m >= 40.0)) return rangeError("block_min_m", block_min_m, "[40, inf)");
  if (!(block_max_m >= block_min_m))
    return rangeError("block_max_m", block_max_m, "[block_min_m, inf)");
  if (!(road_width_m >= 8.0 && road_width_m <= 30.0))
    return rangeError("road_width_m", road_width_m, "[8, 30]");
  if (!(parking_lane_m >= 0.0 && parking_lane_m < 0.25 * road_width_m))
    return rangeError("parking_lane_m", parking_lane_m, "[0, road_width_m / 4)");
  if (!(sidewalk_width_m >= 1.0 && sidewalk_width_m <= 10.0))
    return rangeError("sidewalk_width_m", sidewalk_width_m, "[1, 10]");
  if (!(curb_height_m >= 0.0 && curb_height_m <= 0.4))
    return rangeError("curb_height_m", curb_height_m, "[0, 0.4]");
  if (!(crown_height_m >= 0.0 && crown_height_m <= 0.4))
    return rangeError("crown_height_m", crown_height_m, "[0, 0.4]");
  if (!(building_density >= 0.0 && building_density <= 1.0))
    return rangeError("building_density", building_density, "[0, 1]");
  if (!(building_min_height_m >= 2.0 && building_max_height_m >= building_min_height_m))
    return rangeError("building_max_height_m", building_max_height_m,
                      "[building_min_height_m >= 2, inf)");
  if (!(tree_spacing_m == 0.0 || tree_spacing_m >= 3.0))
    return rangeError("tree_spacing_m", tree_spacing_m, "0 or [3, inf)");
  if (!(tree_probability >= 0.0 && tree_probability <= 1.0))
    return rangeError("tree_probability", tree_probability, "[0, 1]");
  if (!(pole_spacing_m == 0.0 || pole_spacing_m >= 5.0))
    return rangeError("pole_spacing_m", pole_spacing_m, "0 or [5, inf)");
  if (!(parking_slot_m >= 4.5)) return rangeError("parking_slot_m", parking_slot_m, "[4.5, inf)");
  if (!(std::abs(terrain_slope_x) <= 0.08 && std::abs(terrain_slope_y) <= 0.08))
    return rangeError("terrain_slope_x/y",
                      std::max(std::abs(terrain_slope_x), std::abs(terrain_slope_y)),
                      "[-0.08, 0.08]");
  if (!(terrain_wavelength_m >= 100.0))
    return rangeError("terrain_wavelength_m", terrain_wavelength_m, "[100, inf)");
  if (!(ground_mesh_step_m >= 0.5 && ground_mesh_step_m <= 10.0))
    return rangeError("ground_mesh_step_m", ground_mesh_step_m, "[0.5, 10]");
  return Status::success();
}

LaneOffsets Town::laneOffsets() const {
  const double half = 0.5 * config_.road_width_m;
  const double lane = 0.5 * (half - config_.parking_lane_m);
  return {0.5 * lane, 1.5 * lane, half - 0.5 * config_.parking_lane_m};
}

Eigen::AlignedBox2d Town::bounds() const {
  const double m = config_.outer_margin_m + 0.5 * config_.road_width_m;
  return Eigen::AlignedBox2d(Eigen::Vector2d(road_x_.front() - m, road_y_.front() - m),
                             Eigen::Vector2d(road_x_.back() + m, road_y_.back() + m));
}

int Town::nearestLine(const std::vector<double>& lines, double v) {
  auto it = std::lower_bound(lines.begin(), lines.end(), v);
  if (it == lines.begin()) return 0;
  if (it == lines.end()) return static_cast<int>(lines.size()) - 1;
  const int hi = static_cast<int>(it - lines.begin());
  return (v - lines[hi - 1] <= lines[hi] - v) ? hi - 1 : hi;
}

double Town::terrainHeight(double x, double y) const {
  const double k = 2.0 * M_PI / config_.terrain_wavelength_m;
  return config_.terrain_slope_x * x + config_.terrain_slope_y * y +
         config_.terrain_amplitude_m * std::sin(k * x + phase_x_) *
             std::cos(0.77 * k * y + phase_y_);
}

namespace {

/// Lateral distances to the nearest north-south and east-west centrelines, or a negative value
/// where (x, y) is not on that road.
struct RoadHit {
  double dx = -1.0, dy = -1.0;  // |x - X_i|, |y - Y_j| when on those roads
  int i = 0, j = 0;
};

RoadHit locate(const Town& t, double x, double y) {
  RoadHit h;
  const double half = 0.5 * t.config().road_width_m;
  h.i = Town::nearestLine(t.roadX(), x);
  h.j = Town::nearestLine(t.roadY(), y);
  const double ax = std::abs(x - t.roadX()[h.i]), ay = std::abs(y - t.roadY()[h.j]);
  const bool in_y_span = y >= t.roadY().front() - half && y <= t.roadY().back() + half;
  const bool in_x_span = x >= t.roadX().front() - half && x <= t.roadX().back() + half;
  if (ax <= half && in_y_span) h.dx = ax;
  if (ay <= half && in_x_span) h.dy = ay;
  return h;
}

}  // namespace

bool Town::onRoad(double x, double y) const {
  const RoadHit h = locate(*this, x, y);
  return h.dx >= 0.0 || h.dy >= 0.0;
}

double Town::groundHeight(double x, double y) const {
  const RoadHit h = locate(*this, x, y);
  const double t = terrainHeight(x, y);
  if (h.dx < 0.0 && h.dy < 0.0) return t + config_.curb_height_m;
  double d = h.dx >= 0.0 ? h.dx : h.dy;
  if (h.dx >= 0.0 && h.dy >= 0.0) d = std::min(h.dx, h.dy);
  const double u = 2.0 * d / config_.road_width_m;
  return t + config_.crown_height_m * (1.0 - u * u);
}

bool Town::markingAt(double x, double y) const {
  const RoadHit h = locate(*this, x, y);
  const bool on_x = h.dx >= 0.0, on_y = h.dy >= 0.0;
  if (on_x == on_y) return false;  // off road, or inside an intersection square (no paint)
  const double half = 0.5 * config_.road_width_m;
  // r: offset right of travel in the +axis direction; e: distance to the nearest node along the
  // road; along: coordinate along the road; approaching: traffic on this side heads to that node.
  double r, e, along, to_node;
  if (on_x) {
    r = x - road_x_[h.i];
    along = y;
    to_node = road_y_[h.j] - y;
  } else {
    r = road_y_[h.j] - y;
    along = x;
    to_node = road_x_[h.i] - x;
  }
  e = std::abs(to_node) - half;  // distance from the intersection square's edge
  const double a = std::abs(r);
  const double lane = 0.5 * (half - config_.parking_lane_m);
  if (e >= 0.5 && e <= 3.5) return std::fmod(a, 1.0) < 0.5;  // zebra crosswalk
  if (e < 0.5) return false;
  if (e >= 4.0 && e <= 4.45 && r * to_node > 0.0 && a < half - config_.parking_lane_m)
    return true;                            // stop line
  if (a >= 0.06 && a <= 0.18) return true;  // double centre line
  if (std::abs(a - lane) <= 0.06 && std::fmod(std::abs(along), 9.0) < 3.0) return true;
  if (config_.parking_lane_m > 0.0 && std::abs(a - (half - config_.parking_lane_m)) <= 0.06)
    return true;  // parking lane edge
  return false;
}

}  // namespace sim
}  // namespace gmm_localization
