#include "gmm_localization/sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

Status KinematicsConfig::validate() const {
  std::ostringstream os;
  if (!(cruise_speed_mps > 0.5 && cruise_speed_mps <= 40.0))
    os << "cruise_speed_mps = " << cruise_speed_mps << " is outside (0.5, 40]";
  else if (!(max_speed_mps >= cruise_speed_mps * 0.5 && max_speed_mps <= 40.0))
    os << "max_speed_mps = " << max_speed_mps << " is outside [cruise/2, 40]";
  else if (!(max_accel_mps2 > 0.1 && max_accel_mps2 <= 10.0))
    os << "max_accel_mps2 = " << max_accel_mps2 << " is outside (0.1, 10]";
  else if (!(max_decel_mps2 > 0.1 && max_decel_mps2 <= 10.0))
    os << "max_decel_mps2 = " << max_decel_mps2 << " is outside (0.1, 10]";
  else if (!(max_lateral_accel_mps2 > 0.1 && max_lateral_accel_mps2 <= 10.0))
    os << "max_lateral_accel_mps2 = " << max_lateral_accel_mps2 << " is outside (0.1, 10]";
  else if (!(stop_probability >= 0.0 && stop_probability <= 1.0))
    os << "stop_probability = " << stop_probability << " is outside [0, 1]";
  else if (!(stop_min_s >= 0.0 && stop_max_s >= stop_min_s))
    os << "stop_max_s = " << stop_max_s << " is below stop_min_s or negative";
  else if (!(lane_wander_m >= 0.0 && lane_wander_m <= 1.0))
    os << "lane_wander_m = " << lane_wander_m << " is outside [0, 1]";
  if (os.str().empty()) return Status::success();
  return Status::failure("KinematicsConfig." + os.str());
}

Result<Trajectory> Trajectory::create(const Town& town, const Route& route,
                                      const KinematicsConfig& config) {
  const Status valid = config.validate();
  if (!valid) return Result<Trajectory>::failure(valid.error());
  Trajectory tr;
  tr.town_ = &town;
  tr.route_ = &route;
  tr.config_ = config;
  Rng rng(hashKeys(config.seed, 0x7261ull));
  tr.wander_phase_[0] = rng.uniform(0.0, 2.0 * M_PI);
  tr.wander_phase_[1] = rng.uniform(0.0, 2.0 * M_PI);

  // Stations every ~0.25 m, the last one exactly at the end of the route.
  const int n = std::max(2, static_cast<int>(std::ceil(route.length() / 0.25)) + 1);
  tr.ds_ = route.length() / (n - 1);
  const double ds = tr.ds_;
  std::vector<double> vmax(n), dwell(n, 0.0);
  // Cruise speed per stretch between intersections, curvature limit, stops before nodes.
  const auto& st = route.nodeStations();
  const double w = town.config().road_width_m;
  size_t stretch = 0;
  double cruise = std::min(config.max_speed_mps, config.cruise_speed_mps * rng.uniform(0.8, 1.15));
  for (int k = 0; k < n; ++k) {
    const double s = k * ds;
    while (stretch < st.size() && s > st[stretch]) {
      ++stretch;
      cruise = std::min(config.max_speed_mps, config.cruise_speed_mps * rng.uniform(0.8, 1.15));
    }
    const double kappa = std::abs(route.at(s).curvature);
    vmax[k] =
        kappa > 0.0 ? std::min(cruise, std::sqrt(config.max_lateral_accel_mps2 / kappa)) : cruise;
  }
  // Lane wander fades to zero within 15 m of a turn (an offset inside an arc changes the path
  // speed by the factor 1 - kappa * offset, which would jump where the arc ends).
  tr.wander_gain_.assign(n, 1.0f);
  {
    double last_turn = -1e9;
    std::vector<double> dist(n, 1e9);
    for (int k = 0; k < n; ++k) {
      if (route.at(k * ds).curvature != 0.0) last_turn = k * ds;
      dist[k] = k * ds - last_turn;
    }
    last_turn = 1e9;
    for (int k = n - 1; k >= 0; --k) {
      if (route.at(k * ds).curvature != 0.0) last_turn = k * ds;
      const double d = std::min(dist[k], last_turn - k * ds);
      const double u = std::clamp((d - 3.0) / 12.0, 0.0, 1.0);
      tr.wander_gain_[k] = static_cast<float>(u * u * (3.0 - 2.0 * u));
    }
  }
  for (double station : st) {
    if (!rng.bernoulli(config.stop_probability)) continue;
    const int k = static_cast<int>(std::lround((station - 0.5 * w - 8.0) / ds));
    if (k <= 0 || k >= n - 1) continue;
    vmax[k] = 0.0;
    dwell[k] = rng.uniform(config.stop_min_s, config.stop_max_s);
  }
  vmax[0] = vmax[n - 1] = 0.0;
  // Forward (acceleration) and backward (braking) passes: v^2 changes by at most 2 a ds.
  std::vector<double>& v = tr.v_;
  v = vmax;
  for (int k = 1; k < n; ++k)
    v[k] = std::min(v[k], std::sqrt(v[k - 1] * v[k - 1] + 2.0 * config.max_accel_mps2 * ds));
  for (int k = n - 2; k >= 0; --k)
    v[k] = std::min(v[k], std::sqrt(v[k + 1] * v[k + 1] + 2.0 * config.max_decel_mps2 * ds));
  tr.t_in_.assign(n, 0.0);
  tr.t_out_.assign(n, 0.0);
  tr.t_out_[0] = dwell[0];
  for (int k = 1; k < n; ++k) {
    tr.t_in_[k] = tr.t_out_[k - 1] + 2.0 * ds / std::max(1e-9, v[k - 1] + v[k]);
    tr.t_out_[k] = tr.t_in_[k] + dwell[k];
  }
  return tr;
}

double Trajectory::distanceAt(double t) const {
  t = std::clamp(t, 0.0, duration());
  const int n = static_cast<int>(t_in_.size());
  int k = static_cast<int>(std::upper_bound(t_in_.begin(), t_in_.end(), t) - t_in_.begin()) - 1;
  k = std::clamp(k, 0, n - 1);
  if (t <= t_out_[k] || k == n - 1) return std::min(k * ds_, route_->length());
  const double tau = t - t_out_[k];
  const double a = (v_[k + 1] * v_[k + 1] - v_[k] * v_[k]) / (2.0 * ds_);
  return std::min(route_->length(), k * ds_ + std::min(ds_, v_[k] * tau + 0.5 * a * tau * tau));
}

double Trajectory::speedAt(double t) const {
  t = std::clamp(t, 0.0, duration());
  const int n = static_cast<int>(t_in_.size());
  int k = static_cast<int>(std::upper_bound(t_in_.begin(), t_in_.end(), t) - t_in_.begin()) - 1;
  k = std::clamp(k, 0, n - 1);
  if (t <= t_out_[k] || k == n - 1) return v_[k];
  const double a = (v_[k + 1] * v_[k + 1] - v_[k] * v_[k]) / (2.0 * ds_);
  return std::max(0.0, v_[k] + a * (t - t_out_[k]));
}

double Trajectory::timeAtDistance(double s) const {
  s = std::clamp(s, 0.0, route_->length());
  const int k = std::min(static_cast<int>(t_in_.size()) - 1, static_cast<int>(std::floor(s / ds_)));
  const double rest = s - k * ds_;
  if (rest <= 1e-12 || k + 1 >= static_cast<int>(t_in_.size())) return t_in_[k];
  // Solve s = v tau + a tau^2 / 2 on segment k.
  const double a = (v_[k + 1] * v_[k + 1] - v_[k] * v_[k]) / (2.0 * ds_);
  double tau;
  if (std::abs(a) < 1e-12)
    tau = rest / std::max(1e-9, v_[k]);
  else
    tau = (-v_[k] + std::sqrt(std::max(0.0, v_[k] * v_[k] + 2.0 * a * rest))) / a;
  return t_out_[k] + tau;
}

Eigen::Isometry3d Trajectory::poseAtDistance(double s) const {
  const PathPoint p = route_->at(s);
  // Lane wander: two sinusoids; positive offsets move to the right of travel.
  const double k0 = 2.0 * M_PI / wander_wavelength_[0], k1 = 2.0 * M_PI / wander_wavelength_[1];
  const int n = static_cast<int>(wander_gain_.size());
  const double fk = std::clamp(s / ds_, 0.0, n - 1.0);
  const int k = std::min(n - 2, static_cast<int>(fk));
  const double g = wander_gain_[k] + (fk - k) * (wander_gain_[k + 1] - wander_gain_[k]);
  const double dg = (wander_gain_[k + 1] - wander_gain_[k]) / ds_;
  const double a = config_.lane_wander_m;
  const double w =
      a * (0.7 * std::sin(k0 * s + wander_phase_[0]) + 0.3 * std::sin(k1 * s + wander_phase_[1]));
  const double dw = a * (0.7 * k0 * std::cos(k0 * s + wander_phase_[0]) +
                         0.3 * k1 * std::cos(k1 * s + wander_phase_[1]));
  const double off = g * w;
  const double doff = g * dw + dg * w;
  const Eigen::Vector2d fwd0(std::cos(p.heading_rad), std::sin(p.heading_rad));
  const Eigen::Vector2d xy = p.position + Eigen::Vector2d(fwd0.y(), -fwd0.x()) * off;
  const double yaw = p.heading_rad - std::atan(doff);
  const Eigen::Vector2d f(std::cos(yaw), std::sin(yaw)), l(-f.y(), f.x());
  const double hb = 0.5 * config_.wheelbase_m, ht = 0.5 * config_.track_m;
  auto wheel = [&](double df, double dl) {  // tyre footprint average over +-0.4 m
    const Eigen::Vector2d q = xy + f * df + l * dl;
    return (town_->groundHeight(q.x() - 0.4 * f.x(), q.y() - 0.4 * f.y()) +
            town_->groundHeight(q.x(), q.y()) +
            town_->groundHeight(q.x() + 0.4 * f.x(), q.y() + 0.4 * f.y())) /
           3.0;
  };
  const double fl = wheel(hb, ht), fr = wheel(hb, -ht), rl = wheel(-hb, ht), rr = wheel(-hb, -ht);
  const double z = 0.25 * (fl + fr + rl + rr);
  const double pitch = std::atan2(0.5 * (rl + rr - fl - fr), config_.wheelbase_m);  // nose up < 0
  const double roll = std::atan2(0.5 * (fl + rl - fr - rr), config_.track_m);       // left up > 0
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(xy.x(), xy.y(), z);
  return pose;
}

Eigen::Isometry3d Trajectory::pose(double t) const { return poseAtDistance(distanceAt(t)); }

VehicleState Trajectory::state(double t) const {
  const double h = 0.005;
  VehicleState s;
  s.t = t;
  s.distance_m = distanceAt(t);
  s.speed_mps = speedAt(t);
  s.pose = poseAtDistance(s.distance_m);
  const Eigen::Isometry3d a = pose(t - h), b = pose(t + h);
  s.velocity_world = (b.translation() - a.translation()) / (2.0 * h);
  s.acceleration_world = (b.translation() - 2.0 * s.pose.translation() + a.translation()) / (h * h);
  const Eigen::AngleAxisd d(a.linear().transpose() * b.linear());
  s.angular_velocity_body = d.axis() * d.angle() / (2.0 * h);
  return s;
}

}  // namespace sim
}  // namespace gmm_localization
