#include "simulate/simulate_gnss.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "gmm_localization/sim/random.h"
#include "simulate/simulate_imperfection_options.h"

namespace gmm_localization {
namespace tools {

Georeference SimulateGnssOptions::defaultSimulatorGeoreference() {
  Georeference g;
  g.present = true;
  g.utm_zone = 17;
  g.utm_north = true;
  g.origin_easting_m = 277000.0;
  g.origin_northing_m = 4686000.0;
  g.origin_up_m = 250.0;
  g.datum = "WGS84 / UTM zone 17N, heights above the ellipsoid (simulate's default)";
  return g;
}

Result<bool> applyGnssOption(const std::string& name, const std::string& v,
                             SimulateGnssOptions* o) {
  using R = Result<bool>;
  sim::GnssConfig& c = o->config;
  if (name == "--gnss") {
    if (v == "none") {
      c.mode = sim::GnssMode::kNone;
    } else if (v == "realistic") {
      c.mode = sim::GnssMode::kRealistic;
    } else {
      return R::failure("option --gnss: '" + v + "' is not none or realistic");
    }
    return true;
  }
  if (name == "--gnss-outage") {
    auto outage = sim::parseGnssOutage(v);
    if (!outage) return R::failure("option --gnss-outage: " + outage.error());
    c.outages.push_back(*outage);
    o->override_given = name;
    return true;
  }
  if (name == "--utm-zone") {
    auto zone = parseGridZone(v);
    if (!zone) return R::failure("option --utm-zone: " + zone.error());
    o->georeference.utm_zone = zone->zone;
    o->georeference.utm_north = zone->north;
    o->georeference.datum = "WGS84 / UTM zone " + zone->name() + ", heights above the ellipsoid";
    o->override_given = name;
    return true;
  }
  if (name == "--georef-origin") {
    std::stringstream s(v);
    std::string part;
    double e[3];
    int n = 0;
    while (std::getline(s, part, ',')) {
      auto d = parseOptionNumber(name, part);
      if (!d || n >= 3)
        return R::failure("option --georef-origin: expected E,N,U, got '" + v + "'");
      e[n++] = *d;
    }
    if (n != 3) return R::failure("option --georef-origin: expected E,N,U, got '" + v + "'");
    o->georeference.origin_easting_m = e[0];
    o->georeference.origin_northing_m = e[1];
    o->georeference.origin_up_m = e[2];
    o->override_given = name;
    return true;
  }
  double* target = name == "--gnss-rate"       ? &c.rate_hz
                   : name == "--gnss-white"    ? &c.white_sigma_m
                   : name == "--gnss-bias"     ? &c.bias_sigma_m
                   : name == "--gnss-bias-tau" ? &c.bias_tau_s
                                               : nullptr;
  if (name == "--gnss-seed") {
    auto d = parseOptionNumber(name, v);
    if (!d || *d < 0.0 || *d != std::floor(*d))
      return R::failure("option --gnss-seed: '" + v + "' is not a seed (>= 0)");
    c.seed = static_cast<uint64_t>(*d);
    o->seed_given = true;
    o->override_given = name;
    return true;
  }
  if (target == nullptr) return false;
  auto d = parseOptionNumber(name, v);
  if (!d) return R::failure(d.error());
  *target = *d;
  o->override_given = name;
  return true;
}

Status finishGnssOptions(uint64_t pass_derived_seed, SimulateGnssOptions* o) {
  if (o->config.mode == sim::GnssMode::kNone) {
    if (!o->override_given.empty()) {
      return Status::failure("option " + o->override_given +
                             " does nothing without --gnss realistic");
    }
    return Status::success();
  }
  if (!o->seed_given) o->config.seed = sim::hashKeys(pass_derived_seed, 0x6E55ull);
  const Status valid = o->config.validate();
  if (!valid) return valid;
  if (!o->georeference.hasGrid()) return Status::failure("the GNSS georeference has no UTM zone");
  return Status::success();
}

Result<sensor_msgs::NavSatFix> navSatFixFromSample(const sim::GnssSample& s,
                                                   const Georeference& geo, double epoch_s) {
  sensor_msgs::NavSatFix m;
  m.header.stamp = ros::Time(epoch_s + s.t);
  m.header.frame_id = "base_link";
  m.status.service = sensor_msgs::NavSatStatus::SERVICE_GPS;
  if (!s.has_fix) {
    m.status.status = sensor_msgs::NavSatStatus::STATUS_NO_FIX;
    m.latitude = m.longitude = m.altitude = std::numeric_limits<double>::quiet_NaN();
    m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
    return m;
  }
  auto p = mapToGeodetic(geo, s.reported.x(), s.reported.y(), s.reported.z());
  if (!p) return Result<sensor_msgs::NavSatFix>::failure("GNSS fix: " + p.error());
  m.status.status = sensor_msgs::NavSatStatus::STATUS_FIX;
  m.latitude = p->latitude_deg;
  m.longitude = p->longitude_deg;
  m.altitude = p->altitude_m;
  m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  m.position_covariance[0] = m.position_covariance[4] = s.horizontal_sigma_m * s.horizontal_sigma_m;
  m.position_covariance[8] = s.vertical_sigma_m * s.vertical_sigma_m;
  return m;
}

std::string describeGnss(const SimulateGnssOptions& o) {
  const sim::GnssConfig& c = o.config;
  const Georeference& g = o.georeference;
  char line[600];
  std::snprintf(line, sizeof line,
                "gnss: %s at %.1f Hz, white %.2f m + Gauss-Markov bias %.2f m (tau %.0f s) per "
                "horizontal axis (reported sigma %.2f m), %zu outage(s); georeference UTM %s "
                "origin %.3f,%.3f,%.3f (build the map with --utm-zone %s --georef-origin "
                "%.3f,%.3f,%.3f)",
                o.topic.c_str(), c.rate_hz, c.white_sigma_m, c.bias_sigma_m, c.bias_tau_s,
                c.horizontalSigma(), c.outages.size(), g.grid().name().c_str(), g.origin_easting_m,
                g.origin_northing_m, g.origin_up_m, g.grid().name().c_str(), g.origin_easting_m,
                g.origin_northing_m, g.origin_up_m);
  return line;
}

}  // namespace tools
}  // namespace gmm_localization
