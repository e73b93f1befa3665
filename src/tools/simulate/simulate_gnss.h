#pragma once
// Simulated GNSS fixes in simulate's bags (--gnss realistic): the receiver model of
// sim/gnss_model.h, its options, the simulator's georeference (where its world sits on the Earth)
// and the sensor_msgs/NavSatFix messages on /gnss/fix. Off by default (--gnss none): the bag is
// then exactly what it was without these options.

#include <string>
#include <vector>

#include <sensor_msgs/NavSatFix.h>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/georeference.h"
#include "gmm_localization/sim/gnss_model.h"

namespace gmm_localization {
namespace tools {

struct SimulateGnssOptions {
  sim::GnssConfig config;
  bool seed_given = false;     ///< else derived from the pass seed (finishGnssOptions)
  std::string override_given;  ///< the last --gnss-* / georeference option given, if any
  std::string topic = "/gnss/fix";
  /// The simulator's world frame on the Earth: by default UTM 17N with its origin at E 277000,
  /// N 4686000, U 250 m (Ann Arbor, where the paper's vehicle drove; the same origin as the test
  /// fixture's map). Build the drive's map with the same `--utm-zone` and `--georef-origin`.
  Georeference georeference = defaultSimulatorGeoreference();
  static Georeference defaultSimulatorGeoreference();
};

/// Applies option `name` (--gnss, --gnss-*, --utm-zone, --georef-origin) with `value` if it is
/// one of these. True when it was, false when not, or a failure naming the option.
Result<bool> applyGnssOption(const std::string& name, const std::string& value,
                             SimulateGnssOptions* options);

/// After parsing: the default seed from the pass's (INS) seed; validation.
Status finishGnssOptions(uint64_t pass_derived_seed, SimulateGnssOptions* options);

/// The fix message of one sample, stamped epoch + sample time, frame base_link. With a fix:
/// status STATUS_FIX, the reported position converted with mapToGeodetic, covariance
/// DIAGONAL_KNOWN (the model's stationary sigmas, ENU). Without (an outage): status
/// STATUS_NO_FIX, latitude, longitude and altitude NaN, covariance UNKNOWN.
Result<sensor_msgs::NavSatFix> navSatFixFromSample(const sim::GnssSample& sample,
                                                   const Georeference& georeference,
                                                   double epoch_s);

/// One line for simulate's log: the model, the georeference and the build_map arguments.
std::string describeGnss(const SimulateGnssOptions& options);

}  // namespace tools
}  // namespace gmm_localization
