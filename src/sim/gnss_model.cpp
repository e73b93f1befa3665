// GNSS receiver model: white noise plus a first-order Gauss-Markov bias, outages (gnss_model.h).
#include "gmm_localization/sim/gnss_model.h"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace gmm_localization {
namespace sim {

double GnssConfig::horizontalSigma() const {
  return std::sqrt(white_sigma_m * white_sigma_m + bias_sigma_m * bias_sigma_m);
}

bool GnssConfig::inOutage(double t_from_start_s) const {
  for (const GnssOutage& o : outages) {
    if (t_from_start_s >= o.start_s && t_from_start_s < o.start_s + o.duration_s) return true;
  }
  return false;
}

Status GnssConfig::validate() const {
  std::ostringstream os;
  if (!(rate_hz >= 0.1 && rate_hz <= 100.0)) {
    os << "rate_hz = " << rate_hz << " is outside [0.1, 100]";
  } else if (!(white_sigma_m >= 0.0 && white_sigma_m <= 100.0)) {
    os << "white_sigma_m = " << white_sigma_m << " is outside [0, 100]";
  } else if (!(bias_sigma_m >= 0.0 && bias_sigma_m <= 100.0)) {
    os << "bias_sigma_m = " << bias_sigma_m << " is outside [0, 100]";
  } else if (!(horizontalSigma() > 0.0)) {
    os << "white_sigma_m and bias_sigma_m are both 0 (a fix needs a non-zero sigma)";
  } else if (!(bias_tau_s > 0.0 && bias_tau_s <= 1e6)) {
    os << "bias_tau_s = " << bias_tau_s << " is outside (0, 1e6]";
  } else if (!(vertical_factor > 0.0 && vertical_factor <= 10.0)) {
    os << "vertical_factor = " << vertical_factor << " is outside (0, 10]";
  } else {
    for (const GnssOutage& o : outages) {
      if (!(o.start_s >= 0.0 && std::isfinite(o.start_s) && o.duration_s > 0.0 &&
            std::isfinite(o.duration_s))) {
        os << "outage " << o.start_s << ":" << o.duration_s
           << " needs a start >= 0 and a duration > 0";
        break;
      }
    }
  }
  if (os.str().empty()) return Status::success();
  return Status::failure("GnssConfig." + os.str());
}

GnssModel::GnssModel(const GnssConfig& config, double t_begin)
    : config_(config), rng_(config.seed), t_begin_(t_begin) {
  // The bias starts from its stationary distribution (a receiver that has been on for a while).
  for (int k = 0; k < 3; ++k) bias_(k) = config_.bias_sigma_m * rng_.normal();
}

void GnssModel::advanceTo(double t_until, const std::function<Eigen::Vector3d(double)>& truth,
                          std::vector<GnssSample>* out) {
  const double dt = 1.0 / config_.rate_hz;
  const double a = std::exp(-dt / config_.bias_tau_s);
  const double drive = std::sqrt(std::max(0.0, 1.0 - a * a)) * config_.bias_sigma_m;
  const Eigen::Vector3d scale(1.0, 1.0, config_.vertical_factor);
  for (;;) {
    const double t = t_begin_ + static_cast<double>(count_) * dt;
    if (!(t < t_until)) return;
    if (count_ > 0) {
      for (int k = 0; k < 3; ++k) bias_(k) = a * bias_(k) + drive * rng_.normal();
    }
    Eigen::Vector3d white;
    for (int k = 0; k < 3; ++k) white(k) = config_.white_sigma_m * rng_.normal();
    ++count_;
    GnssSample s;
    s.t = t;
    s.has_fix = !config_.inOutage(t - t_begin_);
    s.truth = truth(t);
    s.bias = bias_.cwiseProduct(scale);
    s.error = (bias_ + white).cwiseProduct(scale);
    s.reported = s.truth + s.error;
    s.horizontal_sigma_m = config_.horizontalSigma();
    s.vertical_sigma_m = config_.vertical_factor * s.horizontal_sigma_m;
    if (out != nullptr) out->push_back(s);
  }
}

Result<GnssOutage> parseGnssOutage(const std::string& text) {
  const size_t colon = text.find(':');
  GnssOutage o;
  bool ok = colon != std::string::npos;
  if (ok) {
    const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
    char* end_a = nullptr;
    char* end_b = nullptr;
    o.start_s = std::strtod(a.c_str(), &end_a);
    o.duration_s = std::strtod(b.c_str(), &end_b);
    ok = !a.empty() && !b.empty() && *end_a == '\0' && *end_b == '\0' && std::isfinite(o.start_s) &&
         std::isfinite(o.duration_s) && o.start_s >= 0.0 && o.duration_s > 0.0;
  }
  if (!ok) {
    return Result<GnssOutage>::failure("'" + text +
                                       "' is not START_S:DURATION_S (start >= 0, duration > 0)");
  }
  return o;
}

}  // namespace sim
}  // namespace gmm_localization
