// Map aging: configuration checks and the plan (where the sites, containers, grown trees and
// repaved stretches go). The meshes and the road shading are in map_aging_mesh.cpp.
#include "gmm_localization/sim/map_aging.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {
namespace {

constexpr double kSiteLaneIntrusionM = 0.3;  // fence beyond the parking lane into the traffic lane
constexpr double kSiteSidewalkM = 1.0;       // fence behind the kerb (pedestrians keep >= 1.1 m)
constexpr double kContainerKerbOverhangM = 0.05;  // containers stand flush against the kerb

/// Parking slots grouped into kerb runs: consecutive slots along one kerb between two
/// intersections, in order along the kerb.
std::vector<std::vector<size_t>> kerbRuns(const Town& town) {
  const auto& slots = town.parkingSlots();
  // Key: heading and lateral position of the kerb (rounded); value: (along, slot index).
  std::map<std::pair<long, long>, std::vector<std::pair<double, size_t>>> kerbs;
  for (size_t k = 0; k < slots.size(); ++k) {
    const Eigen::Vector2d along(std::cos(slots[k].yaw_rad), std::sin(slots[k].yaw_rad));
    const Eigen::Vector2d right(along.y(), -along.x());
    kerbs[{std::lround(slots[k].yaw_rad * 1000.0), std::lround(slots[k].center.dot(right) * 100.0)}]
        .push_back({slots[k].center.dot(along), k});
  }
  std::vector<std::vector<size_t>> runs;
  const double max_gap = 1.5 * town.config().parking_slot_m;
  for (auto& entry : kerbs) {
    auto& list = entry.second;
    std::sort(list.begin(), list.end());
    for (size_t k = 0; k < list.size(); ++k) {
      if (k == 0 || list[k].first - list[k - 1].first > max_gap) runs.emplace_back();
      runs.back().push_back(list[k].second);
    }
  }
  return runs;
}

double roadLengthKm(const Town& town) {
  const double x = town.roadX().back() - town.roadX().front();
  const double y = town.roadY().back() - town.roadY().front();
  return 1e-3 * (town.nodesX() * y + town.nodesY() * x);
}

int countFor(double per_km, double km) { return static_cast<int>(std::lround(per_km * km)); }

/// Plans sites and containers over the parking slots (a slot is used once).
class SlotPlanner {
 public:
  SlotPlanner(const Town& town, MapAging& out)
      : town_(town),
        out_(out),
        runs_(kerbRuns(town)),
        where_(town.parkingSlots().size()),
        taken_(town.parkingSlots().size(), 0) {
    for (size_t r = 0; r < runs_.size(); ++r)
      for (size_t p = 0; p < runs_[r].size(); ++p) where_[runs_[r][p]] = {r, p};
    const TownConfig& c = town.config();
    half_lane_ = 0.5 * c.parking_lane_m;
    // A container in a slot: its kerb side just over the kerb line, the rest on the road.
    container_shift_ = half_lane_ + kContainerKerbOverhangM - 0.5 * kContainerWidthM;
  }

  void sites(int n, const MapAgingConfig& config, Rng rng) {
    for (int attempt = 0; attempt < 50 * n && static_cast<int>(out_.sites.size()) < n; ++attempt) {
      const int count = rng.bernoulli(0.5) ? 2 : 3;
      const bool container = rng.bernoulli(config.site_container_probability);
      const auto [r, p] = where_[pick(rng)];
      if (p + count > runs_[r].size()) continue;
      bool free = true;
      for (int q = 0; q < count; ++q) free = free && !taken_[runs_[r][p + q]];
      if (!free) continue;
      for (int q = 0; q < count; ++q) taken_[runs_[r][p + q]] = 1;
      const ParkingSlot& first = slot(runs_[r][p]);
      const ParkingSlot& last = slot(runs_[r][p + count - 1]);
      const double spacing = count > 1 ? (last.center - first.center).norm() / (count - 1) : 0.0;
      ConstructionSite site;
      const Eigen::Vector2d right = rightOf(first);
      // Across the kerb: from 0.3 m into the traffic lane to 1 m onto the sidewalk.
      const double lo = -half_lane_ - kSiteLaneIntrusionM, hi = half_lane_ + kSiteSidewalkM;
      site.fence.center = 0.5 * (first.center + last.center) + right * (0.5 * (lo + hi));
      site.fence.yaw_rad = first.yaw_rad;
      site.fence.half_length_m = 0.5 * count * spacing - 0.25;
      site.fence.half_width_m = 0.5 * (hi - lo);
      site.has_container = container && container_shift_ - 0.5 * kContainerWidthM > lo + 0.05 &&
                           kContainerLengthM < 2.0 * site.fence.half_length_m - 0.6;
      if (site.has_container)
        site.container = containerAt(0.5 * (first.center + last.center), first, 0.0);
      out_.sites.push_back(site);
    }
  }

  void containers(int n, Rng rng) {
    for (int attempt = 0; attempt < 50 * n && static_cast<int>(out_.containers.size()) < n;
         ++attempt) {
      const size_t k = pick(rng);
      const double jitter = rng.uniform(-0.2, 0.2);
      if (taken_[k]) continue;
      taken_[k] = 1;
      out_.containers.push_back(containerAt(slot(k).center, slot(k), jitter));
    }
  }

 private:
  size_t pick(Rng& rng) const {
    return static_cast<size_t>(rng.uniformInt(static_cast<int>(taken_.size())));
  }
  const ParkingSlot& slot(size_t k) const { return town_.parkingSlots()[k]; }
  static Eigen::Vector2d rightOf(const ParkingSlot& s) {
    return {std::sin(s.yaw_rad), -std::cos(s.yaw_rad)};  // toward the kerb
  }
  Footprint containerAt(const Eigen::Vector2d& c, const ParkingSlot& s, double along_m) const {
    Footprint f;
    const Eigen::Vector2d along(std::cos(s.yaw_rad), std::sin(s.yaw_rad));
    f.center = c + rightOf(s) * container_shift_ + along * along_m;
    f.yaw_rad = s.yaw_rad;
    f.half_length_m = 0.5 * kContainerLengthM;
    f.half_width_m = 0.5 * kContainerWidthM;
    return f;
  }

  const Town& town_;
  MapAging& out_;
  std::vector<std::vector<size_t>> runs_;
  std::vector<std::pair<size_t, size_t>> where_;  // slot -> (run, position)
  std::vector<uint8_t> taken_;
  double half_lane_ = 0.0, container_shift_ = 0.0;
};

void planRepaving(const Town& town, const MapAgingConfig& config, int n, Rng rng, MapAging& out) {
  // Road segments between intersection squares, curb to curb; drawn by length.
  struct Segment {
    Eigen::AlignedBox2d box;
    bool north_south;
  };
  const double half = 0.5 * town.config().road_width_m;
  const auto& xs = town.roadX();
  const auto& ys = town.roadY();
  std::vector<Segment> segments;
  std::vector<double> cumulative;
  double total = 0.0;
  auto add = [&](const Segment& s) {
    const Eigen::Vector2d d = s.box.sizes();
    total += s.north_south ? d.y() : d.x();
    segments.push_back(s);
    cumulative.push_back(total);
  };
  for (double x : xs)
    for (size_t j = 0; j + 1 < ys.size(); ++j)
      add({Eigen::AlignedBox2d(Eigen::Vector2d(x - half, ys[j] + half),
                               Eigen::Vector2d(x + half, ys[j + 1] - half)),
           true});
  for (double y : ys)
    for (size_t i = 0; i + 1 < xs.size(); ++i)
      add({Eigen::AlignedBox2d(Eigen::Vector2d(xs[i] + half, y - half),
                               Eigen::Vector2d(xs[i + 1] - half, y + half)),
           false});
  if (segments.empty() || total <= 0.0) return;
  for (int attempt = 0; attempt < 50 * n && static_cast<int>(out.repaved.size()) < n; ++attempt) {
    // A segment with probability proportional to its length, then a stretch inside it.
    const double u = rng.uniform(0.0, total);
    const size_t k = std::min<size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin(),
        segments.size() - 1);
    const Segment& s = segments[k];
    const int axis = s.north_south ? 1 : 0;
    const double seg_len = s.box.sizes()[axis];
    const double len = std::min(seg_len, rng.uniform(config.repaved_min_m, config.repaved_max_m));
    const double start = s.box.min()[axis] + rng.uniform(0.0, seg_len - len);
    RepavedStretch r;
    r.area = s.box;
    r.area.min()[axis] = start;
    r.area.max()[axis] = start + len;
    r.lateral = s.north_south ? Eigen::Vector2d(1.0, 0.0) : Eigen::Vector2d(0.0, 1.0);
    r.repainted = rng.bernoulli(config.repaint_probability);
    const double shift = rng.uniform(config.paint_shift_min_m, config.paint_shift_max_m);
    r.paint_shift_m = r.repainted ? (rng.bernoulli(0.5) ? shift : -shift) : 0.0;
    bool overlap = false;
    for (const RepavedStretch& o : out.repaved) overlap = overlap || o.area.intersects(r.area);
    if (!overlap) out.repaved.push_back(r);
  }
}

Status rangeError(const char* key, double lo, double hi, const char* allowed) {
  std::ostringstream os;
  os << "MapAgingConfig." << key << " = " << lo;
  if (hi != lo) os << ", " << hi;
  os << " is outside " << allowed;
  return Status::failure(os.str());
}

}  // namespace

Result<MapAgingMode> parseMapAgingMode(const std::string& name) {
  if (name == "none") return MapAgingMode::kNone;
  if (name == "realistic") return MapAgingMode::kRealistic;
  return Result<MapAgingMode>::failure("unknown map aging mode '" + name + "' (none or realistic)");
}

Status MapAgingConfig::validate() const {
  auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  if (!in(sites_per_km, 0.0, 50.0))
    return rangeError("sites_per_km", sites_per_km, sites_per_km, "[0, 50]");
  if (!in(containers_per_km, 0.0, 50.0))
    return rangeError("containers_per_km", containers_per_km, containers_per_km, "[0, 50]");
  if (!in(repaved_per_km, 0.0, 50.0))
    return rangeError("repaved_per_km", repaved_per_km, repaved_per_km, "[0, 50]");
  if (!in(site_container_probability, 0.0, 1.0))
    return rangeError("site_container_probability", site_container_probability,
                      site_container_probability, "[0, 1]");
  if (!in(tree_share, 0.0, 1.0)) return rangeError("tree_share", tree_share, tree_share, "[0, 1]");
  if (!in(repaint_probability, 0.0, 1.0))
    return rangeError("repaint_probability", repaint_probability, repaint_probability, "[0, 1]");
  if (!(tree_growth_min_m >= 0.0 && tree_growth_max_m >= tree_growth_min_m &&
        tree_growth_max_m <= 3.0))
    return rangeError("tree_growth_min_m/max_m", tree_growth_min_m, tree_growth_max_m,
                      "0 <= min <= max <= 3");
  if (!(repaved_min_m >= 1.0 && repaved_max_m >= repaved_min_m && repaved_max_m <= 1000.0))
    return rangeError("repaved_min_m/max_m", repaved_min_m, repaved_max_m,
                      "1 <= min <= max <= 1000");
  if (!(paint_shift_min_m >= 0.0 && paint_shift_max_m >= paint_shift_min_m &&
        paint_shift_max_m <= 3.0))
    return rangeError("paint_shift_min_m/max_m", paint_shift_min_m, paint_shift_max_m,
                      "0 <= min <= max <= 3");
  return Status::success();
}

bool Footprint::overlaps(const Footprint& o) const {
  // Separating axis test over the two rectangles' four edge normals.
  const Eigen::Vector2d a[2] = {{std::cos(yaw_rad), std::sin(yaw_rad)},
                                {-std::sin(yaw_rad), std::cos(yaw_rad)}};
  const Eigen::Vector2d b[2] = {{std::cos(o.yaw_rad), std::sin(o.yaw_rad)},
                                {-std::sin(o.yaw_rad), std::cos(o.yaw_rad)}};
  const Eigen::Vector2d d = o.center - center;
  for (const Eigen::Vector2d& axis : {a[0], a[1], b[0], b[1]}) {
    const double ra =
        half_length_m * std::abs(a[0].dot(axis)) + half_width_m * std::abs(a[1].dot(axis));
    const double rb =
        o.half_length_m * std::abs(b[0].dot(axis)) + o.half_width_m * std::abs(b[1].dot(axis));
    if (std::abs(d.dot(axis)) >= ra + rb) return false;
  }
  return true;
}

bool MapAging::blocks(const Footprint& f) const {
  for (const ConstructionSite& s : sites)
    if (s.fence.overlaps(f)) return true;
  for (const Footprint& c : containers)
    if (c.overlaps(f)) return true;
  return false;
}

const RepavedStretch* MapAging::repavedAt(double x, double y) const {
  for (const RepavedStretch& r : repaved)
    if (r.area.contains(Eigen::Vector2d(x, y))) return &r;
  return nullptr;
}

MapAging planMapAging(const Town& town, const MapAgingConfig& config) {
  MapAging out;
  if (config.mode == MapAgingMode::kNone) return out;
  const double km = roadLengthKm(town);
  // One stream per kind of change: a density override leaves the other changes in place.
  SlotPlanner slots(town, out);
  if (!town.parkingSlots().empty()) {
    slots.sites(countFor(config.sites_per_km, km), config, Rng(hashKeys(config.seed, 0x517Eull)));
    slots.containers(countFor(config.containers_per_km, km), Rng(hashKeys(config.seed, 0xC0Eull)));
  }
  for (size_t k = 0; k < town.trees().size(); ++k) {
    if (hashUniform(config.seed, k, 0x7EEull) >= config.tree_share) continue;
    const double u = hashUniform(config.seed, k, 0x7EFull);
    out.grown_trees.push_back(
        {k, config.tree_growth_min_m + u * (config.tree_growth_max_m - config.tree_growth_min_m)});
  }
  planRepaving(town, config, countFor(config.repaved_per_km, km),
               Rng(hashKeys(config.seed, 0x9A7Eull)), out);
  return out;
}

}  // namespace sim
}  // namespace gmm_localization
