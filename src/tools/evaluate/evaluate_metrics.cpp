#include "evaluate/evaluate_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gmm_localization {
namespace eval {

Pose6 toPose6(const PoseStamped2& p) {
  Pose6 o;
  o.x = p.x;
  o.y = p.y;
  o.z = p.z;
  o.roll = p.roll;
  o.pitch = p.pitch;
  o.yaw = p.yaw;
  return o;
}

PoseStamped2 planar(const Pose6& p, double t) {
  PoseStamped2 o;
  o.t = t;
  o.x = p.x;
  o.y = p.y;
  o.z = p.z;
  o.yaw = p.yaw;
  o.roll = p.roll;
  o.pitch = p.pitch;
  return o;
}

bool Trajectory::add(const PoseStamped2& p) {
  if (!std::isfinite(p.t) || (!samples_.empty() && p.t <= samples_.back().t)) return false;
  samples_.push_back(p);
  return true;
}

std::optional<PoseStamped2> Trajectory::at(double t, double max_gap_s) const {
  if (samples_.empty() || !(t >= samples_.front().t && t <= samples_.back().t)) {
    return std::nullopt;
  }
  // First sample with time >= t.
  auto hi = std::lower_bound(samples_.begin(), samples_.end(), t,
                             [](const PoseStamped2& s, double v) { return s.t < v; });
  if (hi->t == t) return *hi;
  const PoseStamped2& b = *hi;
  const PoseStamped2& a = *(hi - 1);
  if (b.t - a.t > max_gap_s) return std::nullopt;
  const double u = (t - a.t) / (b.t - a.t);
  PoseStamped2 p;
  p.t = t;
  p.x = a.x + u * (b.x - a.x);
  p.y = a.y + u * (b.y - a.y);
  p.z = a.z + u * (b.z - a.z);
  p.yaw = wrapAngle(a.yaw + u * wrapAngle(b.yaw - a.yaw));
  p.roll = wrapAngle(a.roll + u * wrapAngle(b.roll - a.roll));
  p.pitch = wrapAngle(a.pitch + u * wrapAngle(b.pitch - a.pitch));
  return p;
}

double wrapAngle(double a) {
  const double w = std::remainder(a, 2.0 * M_PI);  // in [-pi, pi]
  return w <= -M_PI ? w + 2.0 * M_PI : w;
}

double VehicleFrameError::planar_m() const { return std::hypot(longitudinal_m, lateral_m); }

VehicleFrameError vehicleFrameError(const PoseStamped2& estimate, const PoseStamped2& truth) {
  const double ex = estimate.x - truth.x;
  const double ey = estimate.y - truth.y;
  const double c = std::cos(truth.yaw), s = std::sin(truth.yaw);
  VehicleFrameError e;
  e.longitudinal_m = c * ex + s * ey;
  e.lateral_m = -s * ex + c * ey;
  e.yaw_rad = wrapAngle(estimate.yaw - truth.yaw);
  return e;
}

double rms(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();  // no data, not 0 m
  double sum = 0.0;
  for (double x : v) sum += x * x;
  return std::sqrt(sum / static_cast<double>(v.size()));
}

double meanAbs(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (double x : v) sum += std::abs(x);
  return sum / static_cast<double>(v.size());
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

ErrorSummary summarize(const std::vector<VehicleFrameError>& errors) {
  ErrorSummary s;
  s.count = errors.size();
  std::vector<double> lon, lat, yaw, planar;
  for (const VehicleFrameError& e : errors) {
    lon.push_back(e.longitudinal_m);
    lat.push_back(e.lateral_m);
    yaw.push_back(e.yaw_rad);
    planar.push_back(e.planar_m());
  }
  s.rms_longitudinal_m = rms(lon);
  s.rms_lateral_m = rms(lat);
  s.rms_yaw_rad = rms(yaw);
  s.mean_abs_longitudinal_m = meanAbs(lon);
  s.mean_abs_lateral_m = meanAbs(lat);
  if (!planar.empty()) {
    s.p95_planar_m = quantile(planar, 0.95);
    s.max_planar_m = *std::max_element(planar.begin(), planar.end());
  }
  return s;
}

void Confusion::add(bool predicted, bool actual) {
  if (predicted) {
    ++(actual ? tp : fp);
  } else {
    ++(actual ? fn : tn);
  }
}

Confusion& Confusion::operator+=(const Confusion& o) {
  tp += o.tp;
  fp += o.fp;
  fn += o.fn;
  tn += o.tn;
  return *this;
}

double Confusion::precision() const {
  return tp + fp == 0 ? std::numeric_limits<double>::quiet_NaN()
                      : static_cast<double>(tp) / static_cast<double>(tp + fp);
}

double Confusion::recall() const {
  return tp + fn == 0 ? std::numeric_limits<double>::quiet_NaN()
                      : static_cast<double>(tp) / static_cast<double>(tp + fn);
}

double PlanarOffset::distance_m() const { return std::hypot(dx_m, dy_m); }

OffsetSampler::OffsetSampler(uint64_t seed, double radius_m, double max_heading_rad)
    : state_(seed), radius_m_(radius_m), max_heading_rad_(max_heading_rad) {}

double OffsetSampler::uniform() {
  // splitmix64: the same sequence on every platform and standard library (std::mt19937 with
  // std::uniform_real_distribution is not portable across libraries).
  uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

PlanarOffset OffsetSampler::next() {
  // Uniform over the disc: radius ~ R sqrt(u).
  const double r = radius_m_ * std::sqrt(uniform());
  const double a = 2.0 * M_PI * uniform();
  PlanarOffset o;
  o.dx_m = r * std::cos(a);
  o.dy_m = r * std::sin(a);
  o.dyaw_rad = max_heading_rad_ * (2.0 * uniform() - 1.0);
  return o;
}

}  // namespace eval
}  // namespace gmm_localization
