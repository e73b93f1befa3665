#include "gmm_localization/ros/global_start_options.h"

#include <vector>

namespace gmm_localization {
namespace node {

GlobalStartOptions loadGlobalStartOptions(const ParamSource& pnh) {
  GlobalStartOptions o;
  StartSweepOptions& s = o.sweep;
  s.window_half_xy_m = param(pnh, "window_half_xy_m", s.window_half_xy_m, 1.0, 1000.0);
  s.overlap_m = param(pnh, "overlap_m", s.overlap_m, 0.0, 1000.0);
  s.wait_s = param(pnh, "wait_s", s.wait_s, 0.0, 3600.0);
  s.map_wait_s = param(pnh, "map_wait_s", s.map_wait_s, 0.0, 600.0);
  s.attempt_timeout_s = param(pnh, "attempt_timeout_s", s.attempt_timeout_s, 1.0, 3600.0);
  s.max_sweeps = param(pnh, "max_sweeps", s.max_sweeps, 0, 1000000);
  const std::vector<double> centre = param(pnh, "region/centre", std::vector<double>{});
  if (!centre.empty() && centre.size() != 2) {
    throw ConfigError("parameter " + pnh.resolveName("region/centre") +
                      " must be [] (the whole map) or [x, y] in the map frame [m]");
  }
  s.region_radius_m = param(pnh, "region/radius_m", s.region_radius_m, 0.0, 1e6);
  if (centre.size() == 2) {
    s.region_x_m = centre[0];
    s.region_y_m = centre[1];
    if (s.region_radius_m <= 0.0) {
      throw ConfigError("parameter " + pnh.resolveName("region/radius_m") +
                        " must be > 0 when region/centre is set");
    }
  } else if (s.region_radius_m > 0.0) {
    throw ConfigError("parameter " + pnh.resolveName("region/radius_m") +
                      " needs region/centre [x, y]");
  }
  requireValid("global start options", s.validate());
  o.map_frame = param(pnh, "map_frame", o.map_frame);
  if (o.map_frame.empty()) {
    throw ConfigError("parameter " + pnh.resolveName("map_frame") + " must not be empty");
  }
  o.poll_period_s = param(pnh, "poll_period_s", o.poll_period_s, 0.01, 10.0);
  return o;
}

}  // namespace node
}  // namespace gmm_localization
