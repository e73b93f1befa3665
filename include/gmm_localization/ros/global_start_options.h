#pragma once
// Options of the global start nodelet (config/global_start.yaml documents every key), loaded
// once from its private parameters through a ParamSource (params.h).

#include <string>

#include "gmm_localization/core/localization/start_sweep.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct GlobalStartOptions {
  StartSweepOptions sweep;
  std::string map_frame = "map";
  double poll_period_s = 0.2;  ///< how often the sweep is advanced [s, wall]
};

/// Throws ConfigError naming the parameter on a bad value.
GlobalStartOptions loadGlobalStartOptions(const ParamSource& pnh);

}  // namespace node
}  // namespace gmm_localization
