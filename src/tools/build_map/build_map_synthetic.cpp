#include "build_map/build_map_synthetic.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <vector>

namespace gmm_localization {
namespace tools {
namespace {

constexpr double kRoadHalfWidthM = 7.0;
constexpr double kSidewalkOuterM = 11.0;
constexpr double kSidewalkHeightM = 0.15;
constexpr double kCrownM = 0.08;
constexpr double kSensorHeightM = 1.95;
constexpr double kSensorLaneY = -3.5;
constexpr double kMaxRangeM = 100.0;
constexpr double kMinRangeM = 1.0;
constexpr double kRangeNoiseM = 0.02;
constexpr double kFoliageDensity = 1.2;  // mean free path 1/1.2 m inside a canopy

// Intensities (0..255, as a Velodyne reports calibrated reflectivity) of what a ray hits: the
// reflectivity layer's input. Asphalt and lane paint as reflectivity_layer.h has them.
constexpr float kAsphalt = 11.f, kPaint = 110.f, kConcrete = 40.f;
constexpr float kFacade = 60.f, kAwning = 35.f, kCar = 30.f, kTrunk = 20.f, kPole = 50.f,
                kFoliage = 25.f;
constexpr double kLineHalfWidthM = 0.075;  // 0.15 m lines: the centre line and both edges

struct Box {
  Eigen::Vector3d lo, hi;
  float intensity;
};
struct Cylinder {  // vertical
  double x, y, r, z0, z1;
  float intensity;
};
struct Sphere {  // porous canopy
  Eigen::Vector3d c;
  double r;
};

/// The ground's intensity at lateral offset y: asphalt with a painted centre line and edge
/// lines on the road, concrete sidewalks.
float groundIntensity(double y) {
  const double a = std::abs(y);
  if (a >= kRoadHalfWidthM) return kConcrete;
  const double edge = kRoadHalfWidthM - 2.0 * kLineHalfWidthM;  // edge lines end at the curb
  return a <= kLineHalfWidthM || std::abs(a - edge - kLineHalfWidthM) <= kLineHalfWidthM ? kPaint
                                                                                         : kAsphalt;
}

double groundZ(double y) {
  const double a = std::abs(y);
  if (a < kRoadHalfWidthM) return kCrownM * (1.0 - (y / kRoadHalfWidthM) * (y / kRoadHalfWidthM));
  return kSidewalkHeightM;
}

bool hitBox(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t) {
  double t0 = 0.0, t1 = t;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < b.lo[k] || o[k] > b.hi[k]) return false;
      continue;
    }
    double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
    if (t0 > t1) return false;
  }
  t = t0;
  return true;
}

bool hitCylinder(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double& t) {
  const double ox = o.x() - c.x, oy = o.y() - c.y;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a < 1e-12) return false;
  const double b = ox * d.x() + oy * d.y(), cc = ox * ox + oy * oy - c.r * c.r;
  const double disc = b * b - a * cc;
  if (disc < 0.0) return false;
  const double th = (-b - std::sqrt(disc)) / a;
  if (th <= 0.0 || th >= t) return false;
  const double z = o.z() + th * d.z();
  if (z < c.z0 || z > c.z1) return false;
  t = th;
  return true;
}

/// Porous sphere: the ray stops at entry + an exponential depth (u in (0, 1) decides).
bool hitCanopy(const Sphere& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double u,
               double& t) {
  const Eigen::Vector3d oc = o - s.c;
  const double b = oc.dot(d), cc = oc.squaredNorm() - s.r * s.r;
  const double disc = b * b - cc;
  if (disc < 0.0) return false;
  const double t0 = std::max(-b - std::sqrt(disc), 0.0), t1 = -b + std::sqrt(disc);
  const double th = t0 - std::log(u) / kFoliageDensity;
  if (th >= t1 || th >= t || t1 <= 0.0) return false;
  t = th;
  return true;
}

}  // namespace

struct SyntheticStreetSource::World {
  std::vector<Box> boxes;  // buildings, awnings, cars
  std::vector<Cylinder> cylinders;
  std::vector<Sphere> canopies;
  size_t objects = 0;
};

SyntheticStreetSource::SyntheticStreetSource(const SyntheticStreetOptions& o)
    : options_(o), world_(std::make_unique<World>()) {
  std::mt19937 rng(o.seed);
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const double x_lo = -kMaxRangeM, x_hi = o.length_m + kMaxRangeM;
  World& w = *world_;
  for (int side : {-1, 1}) {
    for (double x = x_lo; x < x_hi;) {  // buildings, setbacks, alleys, awnings
      const double len = uni(15.0, 45.0), setback = uni(0.0, 3.0), height = uni(6.0, 30.0);
      const double yf = kSidewalkOuterM + setback;
      Box b{{x, side > 0 ? yf : -yf - 15.0, 0.0},
            {x + len, side > 0 ? yf + 15.0 : -yf, height},
            kFacade};
      w.boxes.push_back(b);
      if (uni(0.0, 1.0) < 0.3) {
        const double a0 = x + 0.2 * len, a1 = x + 0.8 * len;
        w.boxes.push_back(
            {{a0, side > 0 ? yf - 1.5 : -yf, 2.8}, {a1, side > 0 ? yf : -yf + 1.5, 3.0}, kAwning});
      }
      x += len + uni(3.0, 6.0);
    }
    for (double x = x_lo; x < x_hi; x += uni(20.0, 50.0)) {  // second row behind the alleys
      w.boxes.push_back({{x, side > 0 ? 40.0 : -55.0, 0.0},
                         {x + uni(15.0, 45.0), side > 0 ? 55.0 : -40.0, uni(6.0, 30.0)},
                         kFacade});
    }
    for (double x = x_lo; x < x_hi; x += 6.0) {  // parked cars
      if (uni(0.0, 1.0) > 0.6) continue;
      const double cx = x + uni(0.5, 1.1), cy = side * uni(5.9, 6.1);
      w.boxes.push_back({{cx, cy - 0.9, 0.25}, {cx + 4.4, cy + 0.9, 1.5}, kCar});
    }
    for (double x = x_lo; x < x_hi; x += uni(12.0, 20.0)) {  // trees
      const double y = side * 9.5;
      w.cylinders.push_back({x, y, 0.15, 0.0, 3.5, kTrunk});
      w.canopies.push_back({Eigen::Vector3d(x, y, 5.0), uni(1.6, 2.4)});
    }
    for (double x = x_lo + 17.0; x < x_hi; x += 35.0) {  // poles
      w.cylinders.push_back({x, side * 7.6, 0.12, 0.0, 7.0, kPole});
    }
  }
  w.objects = w.boxes.size() + w.cylinders.size() + w.canopies.size();
}

SyntheticStreetSource::~SyntheticStreetSource() = default;

size_t SyntheticStreetSource::sizeHint() const {
  return static_cast<size_t>(std::floor(options_.length_m / options_.scan_spacing_m)) + 1;
}

std::string SyntheticStreetSource::describe() const {
  std::ostringstream s;
  s << "synthetic street " << options_.length_m << " m (seed " << options_.seed << ", "
    << world_->objects << " objects, a scan every " << options_.scan_spacing_m
    << " m, azimuth step " << options_.azimuth_step_deg << " deg)";
  return s.str();
}

Result<bool> SyntheticStreetSource::next(PointBatch& batch) {
  batch.clear();
  if (next_ >= sizeHint()) return false;
  const size_t scan = next_++;
  const double xs = scan * options_.scan_spacing_m;
  const Eigen::Vector3d origin(xs, kSensorLaneY, groundZ(kSensorLaneY) + kSensorHeightM);
  std::mt19937 rng(options_.seed * 1000003u + static_cast<uint32_t>(scan));
  std::normal_distribution<double> noise(0.0, kRangeNoiseM);
  std::uniform_real_distribution<double> unit(1e-9, 1.0);
  const World& w = *world_;
  // Objects that can be within range of this scan.
  std::vector<const Box*> boxes;
  for (const Box& b : w.boxes) {
    if (b.hi.x() > xs - kMaxRangeM && b.lo.x() < xs + kMaxRangeM) boxes.push_back(&b);
  }
  std::vector<const Cylinder*> cyls;
  for (const Cylinder& c : w.cylinders) {
    if (std::abs(c.x - xs) < kMaxRangeM) cyls.push_back(&c);
  }
  std::vector<const Sphere*> canopies;
  for (const Sphere& s : w.canopies) {
    if (std::abs(s.c.x() - xs) < kMaxRangeM) canopies.push_back(&s);
  }
  const int azimuths = static_cast<int>(std::round(360.0 / options_.azimuth_step_deg));
  batch.points_m.reserve(static_cast<size_t>(azimuths) * 32);
  batch.intensity.reserve(static_cast<size_t>(azimuths) * 32);
  for (int laser = 0; laser < 32; ++laser) {
    const double el = (10.67 - laser * (41.34 / 31.0)) * M_PI / 180.0;
    for (int a = 0; a < azimuths; ++a) {
      const double az = (a + 0.5) * 2.0 * M_PI / azimuths;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      double t = kMaxRangeM;
      float intensity = 0.f;  // of the nearest hit so far
      if (d.z() < 0.0) {      // ground: refine on the crowned road / sidewalk height
        double tg = origin.z() / -d.z();
        for (int it = 0; it < 3; ++it)
          tg = (origin.z() - groundZ(origin.y() + tg * d.y())) / -d.z();
        if (tg < t) {
          t = tg;
          intensity = groundIntensity(origin.y() + tg * d.y());
        }
      }
      // Each hit test shortens t only for a nearer hit.
      for (const Box* b : boxes)
        if (hitBox(*b, origin, d, t)) intensity = b->intensity;
      for (const Cylinder* c : cyls)
        if (hitCylinder(*c, origin, d, t)) intensity = c->intensity;
      const double u = unit(rng);
      for (const Sphere* s : canopies)
        if (hitCanopy(*s, origin, d, u, t)) intensity = kFoliage;
      if (t >= kMaxRangeM || t < kMinRangeM) continue;
      const double r = t + noise(rng);
      batch.points_m.push_back((origin + r * d).cast<float>());
      batch.intensity.push_back(intensity);
    }
  }
  batch.has_sensor_origin = true;
  batch.sensor_origin_m = origin;
  // The vehicle frame: base_link on the road under the sensor.
  batch.has_vehicle_origin = true;
  batch.vehicle_origin_m = Eigen::Vector3d(xs, kSensorLaneY, groundZ(kSensorLaneY));
  return true;
}

}  // namespace tools
}  // namespace gmm_localization
