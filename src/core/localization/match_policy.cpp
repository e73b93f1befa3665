#include "gmm_localization/core/localization/match_policy.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "gmm_localization/core/common/option_checks.h"

namespace gmm_localization {
namespace {

template <typename... Checks>
std::string firstError(const Checks&... checks) {
  for (const std::string& e : {checks...}) {
    if (!e.empty()) return e;
  }
  return {};
}

/// Standard deviation of a variance; +inf for a non-finite one (the widest window).
double sigmaOf(double variance) {
  if (!std::isfinite(variance)) return std::numeric_limits<double>::infinity();
  return std::sqrt(std::max(0.0, variance));
}

double clampSigma(double k_sigma, double lo, double hi) {
  if (!std::isfinite(k_sigma)) return hi;
  return std::min(hi, std::max(lo, k_sigma));
}

std::string formatted(const char* what, double value, const char* relation, double limit) {
  std::ostringstream s;
  s.precision(4);
  s << what << " " << value << " " << relation << " " << limit;
  return s.str();
}

}  // namespace

std::string WindowPolicyOptions::validate() const {
  std::string e = firstError(
      rangeProblem("window.sigma_multiplier", sigma_multiplier, 0.5, 10.0),
      rangeProblem("window.min_half_xy_m", min_half_xy_m, 0.2, 100.0),
      rangeProblem("window.max_half_xy_m", max_half_xy_m, 0.2, 100.0),
      rangeProblem("window.min_half_heading_rad", min_half_heading_rad, 0.0, 1.6),
      rangeProblem("window.max_half_heading_rad", max_half_heading_rad, 0.0, 1.6),
      rangeProblem("window.wide_half_xy_m", wide_half_xy_m, 0.2, 100.0),
      rangeProblem("window.wide_half_heading_rad", wide_half_heading_rad, 0.0, 1.6),
      rangeProblem("window.global_max_half_xy_m", global_max_half_xy_m, wide_half_xy_m, 100.0),
      rangeProblem("window.global_max_half_heading_rad", global_max_half_heading_rad,
                   wide_half_heading_rad, M_PI),
      rangeProblem("window.global_widen_factor", global_widen_factor, 1.0, 4.0),
      rangeProblem("window.global_widest_half_xy_m", global_widest_half_xy_m, global_max_half_xy_m,
                   200.0),
      rangeProblem("window.unknown_z_search_m", unknown_z_search_m, 0.0, 20.0),
      rangeProblem("window.interim_half_xy_m", interim_half_xy_m, 0.2, 100.0),
      rangeProblem("window.interim_half_heading_rad", interim_half_heading_rad, 0.0, 1.6));
  if (!e.empty()) return e;
  if (min_half_xy_m > max_half_xy_m) return "window.min_half_xy_m must be <= max_half_xy_m";
  if (min_half_heading_rad > max_half_heading_rad) {
    return "window.min_half_heading_rad must be <= max_half_heading_rad";
  }
  return {};
}

std::string AcceptancePolicyOptions::validate() const {
  return firstError(rangeProblem("acceptance.min_log_likelihood_per_point",
                                 min_log_likelihood_per_point, -100.0, 10.0),
                    rangeProblem("acceptance.min_map_coverage", min_map_coverage, 0.0, 1.0),
                    rangeProblem("acceptance.max_sigma_xy_m", max_sigma_xy_m, 0.0, 1000.0),
                    rangeProblem("acceptance.max_sigma_yaw_rad", max_sigma_yaw_rad, 0.0, 10.0),
                    rangeProblem("acceptance.max_likelihood_drop", max_likelihood_drop, 0.0, 100.0),
                    rangeProblem("acceptance.likelihood_history", likelihood_history, 5, 10000));
}

std::string PoseCovariancePolicyOptions::validate() const {
  return firstError(
      rangeProblem("covariance.search_covariance_scale", search_covariance_scale, 1e-3, 1e3),
      rangeProblem("covariance.fixed_sigma_xy_m", fixed_sigma_xy_m, 1e-4, 100.0),
      rangeProblem("covariance.fixed_sigma_yaw_rad", fixed_sigma_yaw_rad, 1e-5, 3.2),
      rangeProblem("covariance.min_sigma_xy_m", min_sigma_xy_m, 1e-4, 100.0),
      rangeProblem("covariance.min_sigma_yaw_rad", min_sigma_yaw_rad, 1e-5, 3.2),
      rangeProblem("covariance.sigma_z_m", sigma_z_m, 1e-4, 100.0),
      rangeProblem("covariance.sigma_roll_pitch_rad", sigma_roll_pitch_rad, 1e-5, 3.2),
      rangeProblem("covariance.uncertified_min_sigma_xy_m", uncertified_min_sigma_xy_m, 1e-4,
                   1000.0),
      rangeProblem("covariance.uncertified_min_sigma_yaw_rad", uncertified_min_sigma_yaw_rad, 1e-5,
                   3.2));
}

std::string RelocalizationPolicyOptions::validate() const {
  return firstError(
      rangeProblem("relocalization.max_consecutive_rejections", max_consecutive_rejections, 1, 1e6),
      rangeProblem("relocalization.max_posterior_age_s", max_posterior_age_s, 0.0, 60.0),
      rangeProblem("relocalization.max_previous_match_age_s", max_previous_match_age_s, 0.0, 600.0),
      rangeProblem("relocalization.previous_match_sigma_growth_mps",
                   previous_match_sigma_growth_mps, 0.0, 100.0),
      rangeProblem("relocalization.max_stale_prior_age_s", max_stale_prior_age_s, 0.0, 1e6),
      rangeProblem("relocalization.match_history_s", match_history_s, 0.0, 86400.0),
      rangeProblem("relocalization.recall_max_gap_s", recall_max_gap_s, 0.0, 10.0),
      rangeProblem("relocalization.lost_after_rejections", lost_after_rejections, 0, 1000000),
      rangeProblem("relocalization.lost_after_wide_rejections", lost_after_wide_rejections, 0,
                   1000000),
      rangeProblem("relocalization.lost_after_collapses", lost_after_collapses, 0, 1000000),
      rangeProblem("relocalization.jump_posterior_max_gap_m", jump_posterior_max_gap_m, 0.01,
                   1000.0));
}

std::string LocalizationPolicyOptions::validate() const {
  return firstError(window.validate(), acceptance.validate(), covariance.validate(),
                    relocalization.validate());
}

const char* priorSourceName(PriorSource source) {
  switch (source) {
    case PriorSource::kEkf:
      return "ekf";
    case PriorSource::kInitialPose:
      return "initialpose";
    case PriorSource::kConfigured:
      return "configured";
    case PriorSource::kPreviousMatch:
      return "previous_match";
    default:
      return "none";
  }
}

WindowExtent searchWindowFor(const Prior& prior, const WindowPolicyOptions& o) {
  WindowExtent w;
  if (prior.wide && prior.wide_window.half_x_m > 0.0) return prior.wide_window;
  if (prior.wide) {
    w.half_x_m = w.half_y_m = o.wide_half_xy_m;
    w.half_heading_rad = o.wide_half_heading_rad;
    return w;
  }
  // Paper V-B: the search is initialised around the 3-sigma posterior belief.
  const Eigen::Matrix3d& c = prior.covariance_xyh;
  const double k = o.sigma_multiplier;
  w.half_x_m = clampSigma(k * sigmaOf(c(0, 0)), o.min_half_xy_m, o.max_half_xy_m);
  w.half_y_m = clampSigma(k * sigmaOf(c(1, 1)), o.min_half_xy_m, o.max_half_xy_m);
  w.half_heading_rad =
      clampSigma(k * sigmaOf(c(2, 2)), o.min_half_heading_rad, o.max_half_heading_rad);
  return w;
}

double globalHalfExtent(const WindowPolicyOptions& o, int misses) {
  const double base = o.global_max_half_xy_m;
  const double widest = std::max(base, o.global_widest_half_xy_m);
  if (!(o.global_widen_factor > 1.0) || widest <= base || misses <= 0) return base;
  // Sizes base, base f, base f^2, ... up to the first that reaches the widest (capped there);
  // a ratio within 0.1% of a power of f does not add a size of its own.
  const double powers = std::log(widest / base) / std::log(o.global_widen_factor);
  const int sizes = 1 + std::max(1, static_cast<int>(std::ceil(powers - 1e-3)));
  const int k = misses % sizes;
  return std::min(widest, base * std::pow(o.global_widen_factor, k));
}

std::optional<WindowExtent> explicitPoseWindow(const Eigen::Matrix3d& c,
                                               const WindowPolicyOptions& o) {
  const double vx = c(0, 0), vy = c(1, 1), vh = c(2, 2);
  if (!(std::isfinite(vx) && std::isfinite(vy) && std::isfinite(vh) && vx >= 0.0 && vy >= 0.0 &&
        vh >= 0.0)) {
    return std::nullopt;
  }
  const double k = o.sigma_multiplier;
  const double xy = k * std::sqrt(std::max(vx, vy)), h = k * std::sqrt(vh);
  // rviz sends 3 sigma = 45 deg with every "2D Pose Estimate": only a heading said to be unknown
  // (3 sigma of 90 deg or more) widens the heading range.
  const bool heading_unknown = h >= 0.5 * M_PI;
  if (xy <= o.wide_half_xy_m && !heading_unknown) return std::nullopt;
  WindowExtent w;
  w.half_x_m = w.half_y_m = std::clamp(xy, o.wide_half_xy_m, o.global_max_half_xy_m);
  w.half_heading_rad = heading_unknown ? o.global_max_half_heading_rad : o.wide_half_heading_rad;
  return w;
}

SearchWindow discreteWindow(const MatchRequest& request, double heading_step_rad,
                            double resolution_m) {
  return SearchWindow::fromExtent(request.prior, request.half_x_m, request.half_y_m,
                                  request.half_heading_rad, heading_step_rad, resolution_m);
}

namespace {
/// The rules before the likelihood collapse, in acceptMatch's order.
AcceptanceDecision acceptanceRules(const MatchResult& r, const SearchWindow& window,
                                   const AcceptancePolicyOptions& o, bool wide) {
  AcceptanceDecision d;
  const Pose6& p = r.pose;
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
        std::isfinite(p.pitch) && std::isfinite(p.yaw) && r.covariance_xyh.allFinite())) {
    d.reason = "non-finite pose or covariance";
    return d;
  }
  if (r.map_coverage < o.min_map_coverage) {
    d.reason = formatted("map coverage", r.map_coverage, "below", o.min_map_coverage);
    return d;
  }
  if (!(r.log_likelihood_per_point >= o.min_log_likelihood_per_point)) {
    d.reason = formatted("log-likelihood per point", r.log_likelihood_per_point, "below",
                         o.min_log_likelihood_per_point);
    return d;
  }
  const double sx = std::sqrt(std::max(0.0, r.covariance_xyh(0, 0)));
  const double sy = std::sqrt(std::max(0.0, r.covariance_xyh(1, 1)));
  const double sh = std::sqrt(std::max(0.0, r.covariance_xyh(2, 2)));
  if (std::max(sx, sy) > o.max_sigma_xy_m) {
    d.reason =
        formatted("ambiguous: search sigma xy [m]", std::max(sx, sy), "above", o.max_sigma_xy_m);
    return d;
  }
  if (sh > o.max_sigma_yaw_rad) {
    d.reason = formatted("ambiguous: search sigma yaw [rad]", sh, "above", o.max_sigma_yaw_rad);
    return d;
  }
  if (o.reject_on_window_edge) {
    const SearchOutcome& s = r.search;
    const bool edge_x = window.half_x > 0 && (s.tx == 0 || s.tx == 2 * window.half_x);
    const bool edge_y = window.half_y > 0 && (s.ty == 0 || s.ty == 2 * window.half_y);
    const bool edge_h =
        window.half_h > 0 && (s.heading_index == 0 || s.heading_index == 2 * window.half_h);
    if (edge_x || edge_y || edge_h) {
      d.reason = std::string("optimum on the search window's edge (") + (edge_x ? "x " : "") +
                 (edge_y ? "y " : "") + (edge_h ? "heading " : "") +
                 "): the prior may be too far off";
      return d;
    }
  }
  if (o.require_certificate && !r.certificate.certified) {
    d.reason = std::string("uncertified: ") + certificateFailureName(r.certificate.failure);
    return d;
  }
  if (wide && o.require_certificate_wide && !r.certificate.certified &&
      r.certificate.failure != CertificateFailure::kDisabled) {
    d.reason = std::string("uncertified in a ") + (r.global ? "global" : "wide") +
               " window: " + certificateFailureName(r.certificate.failure);
    return d;
  }
  d.accepted = true;
  return d;
}
}  // namespace

AcceptanceDecision acceptMatch(const MatchResult& r, const SearchWindow& window,
                               const AcceptancePolicyOptions& o, bool wide, double recent_ll,
                               bool interim) {
  AcceptanceDecision d = acceptanceRules(r, window, o, wide);
  // The collapse is noted whatever rule rejects the match (a kidnapped scan often ends on the
  // window's edge too), and rejects an otherwise acceptable one. An interim window (around an
  // estimate the matcher has lost) counts a certified match too: a window without the truth
  // may hold one unique wrong optimum.
  const bool applies = interim || (!wide && !r.certificate.certified &&
                                   r.certificate.failure != CertificateFailure::kDisabled);
  d.likelihood_collapsed = applies && o.max_likelihood_drop > 0.0 && std::isfinite(recent_ll) &&
                           r.log_likelihood_per_point < recent_ll - o.max_likelihood_drop;
  if (d.accepted && d.likelihood_collapsed) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(2) << "likelihood collapsed: log-likelihood per point "
      << r.log_likelihood_per_point << ", " << recent_ll - r.log_likelihood_per_point
      << " below the recent median " << recent_ll << ", "
      << (r.certificate.certified
              ? std::string("certified in an interim window")
              : "uncertified (" + std::string(certificateFailureName(r.certificate.failure)) + ")");
    d.accepted = false;
    d.reason = s.str();
  }
  return d;
}

Matrix6d publishedPoseCovariance(const Eigen::Matrix3d& search,
                                 const PoseCovariancePolicyOptions& o, bool certified) {
  Eigen::Matrix3d xyh = Eigen::Matrix3d::Zero();
  const bool usable = o.use_search_covariance && search.allFinite();
  if (usable) {
    xyh = 0.5 * (search + search.transpose()) * o.search_covariance_scale;
  } else {
    xyh.diagonal() << o.fixed_sigma_xy_m * o.fixed_sigma_xy_m,
        o.fixed_sigma_xy_m * o.fixed_sigma_xy_m, o.fixed_sigma_yaw_rad * o.fixed_sigma_yaw_rad;
  }
  // Floors: raise a too small diagonal entry, scaling its correlations so the matrix stays
  // positive semi-definite (D^T C D with D >= 1), then make sure it is positive definite.
  const double min_xy =
      certified ? o.min_sigma_xy_m : std::max(o.min_sigma_xy_m, o.uncertified_min_sigma_xy_m);
  const double min_yaw = certified ? o.min_sigma_yaw_rad
                                   : std::max(o.min_sigma_yaw_rad, o.uncertified_min_sigma_yaw_rad);
  const double floors[3] = {min_xy, min_xy, min_yaw};
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  for (int i = 0; i < 3; ++i) {
    const double var = xyh(i, i);
    const double min_var = floors[i] * floors[i];
    if (!(var >= min_var)) scale(i) = var > 0.0 ? std::sqrt(min_var / var) : 0.0;
  }
  for (int i = 0; i < 3; ++i) {
    if (scale(i) == 0.0) {  // a zero (or negative) variance: drop its correlations
      xyh.row(i).setZero();
      xyh.col(i).setZero();
      xyh(i, i) = floors[i] * floors[i];
      scale(i) = 1.0;
    }
  }
  xyh = scale.asDiagonal() * xyh * scale.asDiagonal();
  // Guard against indefinite input (only possible with strongly inconsistent search output).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(xyh);
  if (eig.eigenvalues().minCoeff() <= 0.0) {
    xyh = xyh.diagonal().asDiagonal();
  }

  Matrix6d c = poseCovarianceFromPlanar(xyh);
  c(2, 2) = o.sigma_z_m * o.sigma_z_m;  // z, roll, pitch of (x, y, z, roll, pitch, yaw)
  c(3, 3) = c(4, 4) = o.sigma_roll_pitch_rad * o.sigma_roll_pitch_rad;
  return c;
}

}  // namespace gmm_localization
