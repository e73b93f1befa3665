#include "gmm_localization/sim/pass.h"

#include <cmath>
#include <sstream>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

const char* passTypeName(PassType type) {
  switch (type) {
    case PassType::kMapping:
      return "mapping";
    case PassType::kDowntown:
      return "downtown";
    default:
      return "snowy";
  }
}

Result<PassType> parsePassType(const std::string& name) {
  if (name == "mapping") return PassType::kMapping;
  if (name == "downtown") return PassType::kDowntown;
  if (name == "snowy") return PassType::kSnowy;
  return Result<PassType>::failure("unknown pass type '" + name + "' (mapping, downtown or snowy)");
}

PassConfig PassConfig::defaults(PassType type, uint64_t seed) {
  PassConfig c;
  c.type = type;
  c.seed = seed;
  c.aging.seed = hashKeys(static_cast<uint64_t>(type), seed, 0xA6Eull);
  if (type == PassType::kDowntown) {
    c.moving_cars_per_km2 = 40.0;
    c.pedestrians_per_km2 = 150.0;
  } else if (type == PassType::kSnowy) {
    c.moving_cars_per_km2 = 25.0;
    c.pedestrians_per_km2 = 60.0;
    c.snow = true;
  }
  return c;
}

Status PassConfig::validate() const {
  std::ostringstream os;
  if (!(parked_occupancy >= 0.0 && parked_occupancy <= 1.0))
    os << "parked_occupancy = " << parked_occupancy << " is outside [0, 1]";
  else if (!(parked_keep_probability >= 0.0 && parked_keep_probability <= 1.0))
    os << "parked_keep_probability = " << parked_keep_probability << " is outside [0, 1]";
  else if (!(moving_cars_per_km2 >= 0.0 && moving_cars_per_km2 <= 1000.0))
    os << "moving_cars_per_km2 = " << moving_cars_per_km2 << " is outside [0, 1000]";
  else if (!(pedestrians_per_km2 >= 0.0 && pedestrians_per_km2 <= 5000.0))
    os << "pedestrians_per_km2 = " << pedestrians_per_km2 << " is outside [0, 5000]";
  else if (!(snow_depth_min_m >= 0.0 && snow_depth_max_m >= snow_depth_min_m &&
             snow_depth_max_m <= 0.5))
    os << "snow depth [" << snow_depth_min_m << ", " << snow_depth_max_m
       << "] is not within [0, 0.5]";
  else if (!(snowbank_max_height_m >= 0.0 && snowbank_max_height_m <= 2.0))
    os << "snowbank_max_height_m = " << snowbank_max_height_m << " is outside [0, 2]";
  else if (!(snowbank_coverage >= 0.0 && snowbank_coverage <= 1.0))
    os << "snowbank_coverage = " << snowbank_coverage << " is outside [0, 1]";
  else if (!(snowfall_returns_per_ray >= 0.0 && snowfall_returns_per_ray <= 0.5))
    os << "snowfall_returns_per_ray = " << snowfall_returns_per_ray << " is outside [0, 0.5]";
  else if (!(snowfall_mean_range_m > 0.0 && snowfall_max_range_m >= 1.0))
    os << "snowfall ranges must be positive (mean " << snowfall_mean_range_m << ", max "
       << snowfall_max_range_m << ")";
  if (!os.str().empty()) return Status::failure(std::string("PassConfig.") + os.str());
  return aging.validate();
}

bool Actor::continuousOver(double t0, double t1) const {
  if (kind == Kind::kPedestrian) return true;
  const double len = (b - a).norm();
  return std::floor((phase_m + speed_mps * t0) / len) ==
         std::floor((phase_m + speed_mps * t1) / len);
}

bool Actor::poseAt(const Town& town, double t, Eigen::Isometry3d* pose) const {
  const double len = (b - a).norm();
  const Eigen::Vector2d dir = (b - a) / len;
  double u = phase_m + speed_mps * t;
  double yaw = std::atan2(dir.y(), dir.x());
  if (kind == Kind::kCar) {
    u = u - std::floor(u / len) * len;
  } else {  // back and forth
    double w = u - std::floor(u / (2.0 * len)) * 2.0 * len;
    if (w > len) {
      w = 2.0 * len - w;
      yaw += M_PI;
    }
    u = w;
  }
  const Eigen::Vector2d p = a + dir * u;
  pose->setIdentity();
  pose->linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose->translation() = Eigen::Vector3d(p.x(), p.y(), town.groundHeight(p.x(), p.y()));
  return true;
}

PassContents preparePass(const Town& town, const PassConfig& config) {
  PassContents out;
  out.config = config;
  const uint64_t town_seed = town.config().seed;
  const bool mapping = config.type == PassType::kMapping;
  const auto& slots = town.parkingSlots();
  for (size_t k = 0; k < slots.size(); ++k) {
    // The mapping arrangement depends on the town only, so every pass agrees on it.
    bool occupied = hashUniform(town_seed, k, 0x50ull) < config.parked_occupancy;
    uint64_t car_key = hashKeys(town_seed, k, 0x51ull);
    uint8_t label = kLabelStatic;
    if (!mapping && hashUniform(config.seed, k, 0x52ull) >= config.parked_keep_probability) {
      occupied = hashUniform(config.seed, k, 0x53ull) < config.parked_occupancy;
      car_key = hashKeys(config.seed, k, 0x54ull);
      label = kLabelDynamic;
    }
    if (!occupied) continue;
    Rng rng(car_key);
    const CarShape shape = randomCarShape(rng);
    const Eigen::Vector2d along(std::cos(slots[k].yaw_rad), std::sin(slots[k].yaw_rad));
    out.parked.push_back({slots[k].center + along * rng.uniform(-0.4, 0.4),
                          slots[k].yaw_rad + rng.uniform(-0.02, 0.02), shape, label});
  }

  const Eigen::AlignedBox2d grid(town.nodePosition(0, 0),
                                 town.nodePosition(town.nodesX() - 1, town.nodesY() - 1));
  const double area_km2 = grid.volume() * 1e-6;
  Rng rng(hashKeys(config.seed, 0xAC7ull, static_cast<uint64_t>(config.type)));
  const int cars = static_cast<int>(std::lround(config.moving_cars_per_km2 * area_km2));
  const double inner = town.laneOffsets().inner_m;
  for (int k = 0; k < cars; ++k) {
    Actor a;
    a.kind = Actor::Kind::kCar;
    const bool north_south = rng.bernoulli(0.5);
    const bool positive = rng.bernoulli(0.5);
    Eigen::Vector2d p0, p1;
    if (north_south) {
      const double x = town.roadX()[rng.uniformInt(town.nodesX())];
      p0 = {x, town.roadY().front()};
      p1 = {x, town.roadY().back()};
    } else {
      const double y = town.roadY()[rng.uniformInt(town.nodesY())];
      p0 = {town.roadX().front(), y};
      p1 = {town.roadX().back(), y};
    }
    if (!positive) std::swap(p0, p1);
    const Eigen::Vector2d d = (p1 - p0).normalized();
    const Eigen::Vector2d right(d.y(), -d.x());
    a.a = p0 + right * inner;
    a.b = p1 + right * inner;
    a.speed_mps = rng.uniform(6.0, 12.0);
    a.phase_m = rng.uniform(0.0, (a.b - a.a).norm());
    a.shape = randomCarShape(rng);
    out.actors.push_back(a);
  }
  const int walkers = static_cast<int>(std::lround(config.pedestrians_per_km2 * area_km2));
  const auto& ways = town.walkways();
  for (int k = 0; k < walkers && !ways.empty(); ++k) {
    const Walkway& w = ways[rng.uniformInt(static_cast<int>(ways.size()))];
    const Eigen::Vector2d d = (w.b - w.a).normalized();
    const Eigen::Vector2d side(-d.y(), d.x());
    const double off = rng.uniform(-0.9, 0.9);
    Actor a;
    a.kind = Actor::Kind::kPedestrian;
    a.a = w.a + side * off;
    a.b = w.b + side * off;
    a.speed_mps = rng.uniform(1.0, 1.6);
    a.phase_m = rng.uniform(0.0, 2.0 * (a.b - a.a).norm());
    out.actors.push_back(a);
  }
  return out;
}

}  // namespace sim
}  // namespace gmm_localization
