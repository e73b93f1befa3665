#pragma once
// GnssModel: a stand-alone GNSS receiver (single-frequency code solution, as the paper's
// reflectivity baseline used "with GPS"), off by default. At rate_hz it reports the position of
// base_link (the receiver's lever arm already applied, as an INS-coupled receiver does) in the
// map frame with an error
//     e_k = b_k + w_k,   w_k ~ N(0, white_sigma_m^2) per axis, independent between fixes,
//     b_{k+1} = a b_k + sqrt(1 - a^2) bias_sigma_m n_k,   a = exp(-dt / bias_tau_s),
// a first-order Gauss-Markov bias (multipath, ionosphere, orbit errors) started from its
// stationary distribution, so that e has the stationary variance bias_sigma_m^2 +
// white_sigma_m^2 per horizontal axis at any time and the bias's autocorrelation is
// exp(-|lag| / bias_tau_s). The vertical error is the same model scaled by vertical_factor.
// The reported sigma (horizontal and vertical) is the whole stationary error's: honest per fix,
// but the fixes are correlated through b, which the reported covariance cannot say.
//
// Outages (start and duration from the segment start): no solution (GnssSample::has_fix false);
// the bias keeps evolving through them. Deterministic: one sequential stream from `seed`, one
// draw per fix and axis whatever the outages. Units: metres, seconds; axes of the map frame
// (the simulator's world; its georeference turns them into the UTM grid, in which an isotropic
// horizontal error is the same as in ENU).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

enum class GnssMode { kNone, kRealistic };

struct GnssOutage {
  double start_s = 0.0;     ///< from the segment start [s]
  double duration_s = 0.0;  ///< [s], > 0
};

struct GnssConfig {
  GnssMode mode = GnssMode::kNone;
  uint64_t seed = 31;
  double rate_hz = 5.0;
  double white_sigma_m = 0.5;  ///< per horizontal axis, independent between fixes
  double bias_sigma_m = 1.0;   ///< stationary sigma of the Gauss-Markov bias, per horizontal axis
  double bias_tau_s = 60.0;    ///< its correlation time
  double vertical_factor = 1.5;
  std::vector<GnssOutage> outages;

  /// Total stationary error sigma per horizontal axis [m] (what the fix reports).
  double horizontalSigma() const;
  /// True when t (from the segment start) falls in an outage.
  bool inOutage(double t_from_start_s) const;
  Status validate() const;
};

struct GnssSample {
  double t = 0.0;  ///< trajectory time [s]
  bool has_fix = true;
  Eigen::Vector3d truth = Eigen::Vector3d::Zero();     ///< base_link in map [m]
  Eigen::Vector3d error = Eigen::Vector3d::Zero();     ///< reported - truth [m]
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();      ///< the Gauss-Markov part of error [m]
  Eigen::Vector3d reported = Eigen::Vector3d::Zero();  ///< truth + error [m]
  double horizontal_sigma_m = 0.0;                     ///< reported, per axis
  double vertical_sigma_m = 0.0;
};

class GnssModel {
 public:
  /// Fixes at t_begin + k / rate_hz.
  GnssModel(const GnssConfig& config, double t_begin);
  /// Appends the fixes with time in [current, t_until), truth(t) giving base_link's map position.
  void advanceTo(double t_until, const std::function<Eigen::Vector3d(double)>& truth,
                 std::vector<GnssSample>* out);

 private:
  GnssConfig config_;
  Rng rng_;
  double t_begin_ = 0.0;
  long count_ = 0;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
};

/// Parses "START_S:DURATION_S" (both >= 0, duration > 0). Fails naming the text.
Result<GnssOutage> parseGnssOutage(const std::string& text);

}  // namespace sim
}  // namespace gmm_localization
