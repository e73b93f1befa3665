#include "gmm_localization/sim/map_pose_error.h"

#include <cmath>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

namespace {

constexpr int kAxes = 6;            // x, y, z, roll, pitch, yaw
constexpr double kKnotM = 5.0;      // drift random-walk step [m of path]
constexpr int kWaves = 4;           // sinusoids per residual axis
constexpr double kMinWaveM = 40.0;  // residual wavelengths [m]
constexpr double kMaxWaveM = 160.0;

/// One axis: a random walk sampled every kKnotM metres, linearly interpolated.
class Walk {
 public:
  Walk(Rng rng, double sigma_per_100m, double length_m) {
    const double step = sigma_per_100m * std::sqrt(kKnotM / 100.0);
    const size_t n = static_cast<size_t>(std::ceil(length_m / kKnotM)) + 2;
    knots_.assign(n, 0.0);
    for (size_t k = 1; k < n; ++k) knots_[k] = knots_[k - 1] + step * rng.normal();
  }
  double at(double s) const {
    const double u = std::max(0.0, s / kKnotM);
    const size_t k = std::min(static_cast<size_t>(u), knots_.size() - 2);
    const double f = std::min(1.0, u - static_cast<double>(k));
    return knots_[k] + f * (knots_[k + 1] - knots_[k]);
  }

 private:
  std::vector<double> knots_;
};

/// One axis: sum of kWaves sinusoids in distance, RMS `rms` over a long path.
class Waves {
 public:
  Waves(Rng rng, double rms) : amp_(rms / std::sqrt(0.5 * kWaves)) {
    for (int k = 0; k < kWaves; ++k) {
      wavenumber_[k] = 2.0 * M_PI / rng.uniform(kMinWaveM, kMaxWaveM);
      phase_[k] = rng.uniform(0.0, 2.0 * M_PI);
    }
  }
  double at(double s) const {
    double v = 0.0;
    for (int k = 0; k < kWaves; ++k) v += std::sin(wavenumber_[k] * s + phase_[k]);
    return amp_ * v;
  }

 private:
  double amp_;
  double wavenumber_[kWaves] = {};
  double phase_[kWaves] = {};
};

std::vector<double> pathLength(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> s(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i)
    s[i] = s[i - 1] + (poses[i].translation() - poses[i - 1].translation()).norm();
  return s;
}

bool finiteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

Result<MapPoseErrorMode> parseMapPoseErrorMode(const std::string& name) {
  if (name == "none") return MapPoseErrorMode::kNone;
  if (name == "realistic") return MapPoseErrorMode::kRealistic;
  return Result<MapPoseErrorMode>::failure("map pose error mode must be none or realistic, got '" +
                                           name + "'");
}

Status MapPoseErrorConfig::validate() const {
  const struct {
    const char* name;
    double v;
  } nonneg[] = {{"drift per 100 m [m]", drift_m_per_100m},
                {"drift per 100 m [deg]", drift_deg_per_100m},
                {"residual [m]", residual_m},
                {"residual [deg]", residual_deg}};
  for (const auto& n : nonneg)
    if (!finiteNonNegative(n.v))
      return Status::failure(std::string("map pose error: ") + n.name +
                             " must be finite and >= 0, got " + std::to_string(n.v));
  if (!std::isfinite(loop_radius_m) || loop_radius_m <= 0.0)
    return Status::failure("map pose error: loop radius must be > 0 m, got " +
                           std::to_string(loop_radius_m));
  if (!std::isfinite(min_loop_m) || min_loop_m <= 0.0)
    return Status::failure("map pose error: minimum loop length must be > 0 m, got " +
                           std::to_string(min_loop_m));
  return Status::success();
}

std::vector<size_t> MapPoseError::closures(const std::vector<Eigen::Isometry3d>& truth) const {
  const std::vector<double> s = pathLength(truth);
  const double r2 = config_.loop_radius_m * config_.loop_radius_m;
  std::vector<size_t> out;
  for (size_t i = 0; i < truth.size(); ++i) {
    for (size_t j = 0; j < i && s[i] - s[j] >= config_.min_loop_m; ++j) {
      if ((truth[i].translation() - truth[j].translation()).squaredNorm() < r2) {
        out.push_back(i);
        break;
      }
    }
  }
  return out;
}

std::vector<Eigen::Isometry3d> MapPoseError::apply(
    const std::vector<Eigen::Isometry3d>& truth) const {
  if (config_.mode == MapPoseErrorMode::kNone || truth.empty()) return truth;
  const std::vector<double> s = pathLength(truth);
  const Rng root(config_.seed);
  const double deg = M_PI / 180.0;
  std::vector<Walk> drift;
  std::vector<Waves> residual;
  for (int a = 0; a < kAxes; ++a) {
    const bool trans = a < 3;
    drift.emplace_back(root.fork(2 * a),
                       trans ? config_.drift_m_per_100m : config_.drift_deg_per_100m * deg,
                       s.back());
    residual.emplace_back(
        root.fork(2 * a + 1),
        (trans ? config_.residual_m : config_.residual_deg * deg) / std::sqrt(3.0));
  }
  // Anchors: the start and every closure; the drift is pinned to zero there.
  std::vector<size_t> anchors{0};
  for (size_t c : closures(truth))
    if (c != anchors.back()) anchors.push_back(c);

  std::vector<Eigen::Isometry3d> out(truth.size());
  size_t seg = 0;  // anchors[seg] <= i
  for (size_t i = 0; i < truth.size(); ++i) {
    while (seg + 1 < anchors.size() && anchors[seg + 1] <= i) ++seg;
    const double sa = s[anchors[seg]];
    const bool bracketed = seg + 1 < anchors.size();
    const double sb = bracketed ? s[anchors[seg + 1]] : sa;
    const double f = (bracketed && sb > sa) ? (s[i] - sa) / (sb - sa) : 0.0;
    double e[kAxes];
    for (int a = 0; a < kAxes; ++a) {
      const double da = drift[a].at(sa);
      const double db = bracketed ? drift[a].at(sb) : da;
      e[a] = residual[a].at(s[i]) + drift[a].at(s[i]) - (da + f * (db - da));
    }
    const Eigen::Matrix3d r_err = (Eigen::AngleAxisd(e[5], Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(e[4], Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(e[3], Eigen::Vector3d::UnitX()))
                                      .toRotationMatrix();
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = r_err * truth[i].linear();
    p.translation() = truth[i].translation() + Eigen::Vector3d(e[0], e[1], e[2]);
    out[i] = p;
  }
  return out;
}

}  // namespace sim
}  // namespace gmm_localization
