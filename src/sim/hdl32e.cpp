#include "gmm_localization/sim/hdl32e.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gmm_localization {
namespace sim {

Status Hdl32eConfig::validate() const {
  std::ostringstream os;
  if (!(rotation_rate_hz >= 5.0 && rotation_rate_hz <= 20.0))
    os << "rotation_rate_hz = " << rotation_rate_hz << " is outside [5, 20]";
  else if (!(firing_decimation >= 1 && firing_decimation <= 64))
    os << "firing_decimation = " << firing_decimation << " is outside [1, 64]";
  else if (!(min_range_m >= 0.0 && max_range_m > min_range_m && max_range_m <= 200.0))
    os << "range [" << min_range_m << ", " << max_range_m << "] is not within [0, 200]";
  else if (!(range_noise_m >= 0.0 && range_noise_m <= 1.0))
    os << "range_noise_m = " << range_noise_m << " is outside [0, 1]";
  else if (!(dropout_probability >= 0.0 && dropout_probability < 1.0))
    os << "dropout_probability = " << dropout_probability << " is outside [0, 1)";
  else if (!(intensity_noise >= 0.0))
    os << "intensity_noise = " << intensity_noise << " is negative";
  else if (!(detection_threshold >= 0.0))
    os << "detection_threshold = " << detection_threshold << " is negative";
  if (os.str().empty()) return Status::success();
  return Status::failure("Hdl32eConfig." + os.str());
}

const std::array<double, Hdl32eModel::kLasers>& Hdl32eModel::elevationsDeg() {
  // Interleaved: even ids climb from -30.67, odd ids from -9.33, in steps of 4/3 deg.
  static const std::array<double, kLasers> kTable = [] {
    std::array<double, kLasers> t{};
    for (int id = 0; id < kLasers; ++id) {
      const int k = (id % 2 == 0) ? id / 2 : 16 + id / 2;
      t[id] = -30.67 + k * (41.34 / 31.0);
    }
    return t;
  }();
  return kTable;
}

int Hdl32eModel::ringOfLaser(int laser) { return (laser % 2 == 0) ? laser / 2 : 16 + laser / 2; }

Hdl32eModel::Hdl32eModel(const Hdl32eConfig& config) : config_(config) {
  firing_period_ = kFiringCycleS * std::max(1, config.firing_decimation);
  firings_ = static_cast<int>(std::floor(revolutionPeriod() / firing_period_ + 1e-9));
  dirs_.resize(static_cast<size_t>(firings_) * kLasers);
  const auto& el = elevationsDeg();
  for (int f = 0; f < firings_; ++f) {
    const double az = azimuth(f);
    for (int l = 0; l < kLasers; ++l) {
      const double e = el[l] * M_PI / 180.0;
      dirs_[f * kLasers + l] = Eigen::Vector3f(static_cast<float>(std::cos(e) * std::cos(az)),
                                               static_cast<float>(std::cos(e) * std::sin(az)),
                                               static_cast<float>(std::sin(e)));
    }
  }
}

double Hdl32eModel::azimuthStepDeg() const {
  return 360.0 * firing_period_ * config_.rotation_rate_hz;
}

double Hdl32eModel::azimuth(int firing) const {
  return (config_.start_azimuth_deg - firing * azimuthStepDeg()) * M_PI / 180.0;
}

}  // namespace sim
}  // namespace gmm_localization
