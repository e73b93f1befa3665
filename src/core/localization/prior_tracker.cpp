#include "gmm_localization/core/localization/prior_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace {

bool finiteSample(const OdometrySample& s) {
  return std::isfinite(s.stamp_s) && s.odom_T_base.matrix().allFinite() &&
         s.linear_mps.allFinite() && s.angular_radps.allFinite();
}

/// Motion over dt [s] at constant body twist: translation v dt, rotation exp(w dt).
Eigen::Isometry3d constantTwistMotion(const BodyTwist& t, double dt) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d rv = t.angular_radps * dt;
  const double angle = rv.norm();
  if (angle > 1e-12) m.linear() = Eigen::AngleAxisd(angle, rv / angle).toRotationMatrix();
  m.translation() = t.linear_mps * dt;
  return m;
}

}  // namespace

// ---- OdometryBuffer -------------------------------------------------------------------------

OdometryBuffer::AddResult OdometryBuffer::add(const OdometrySample& sample) {
  if (!finiteSample(sample)) return AddResult::kDroppedOutOfOrder;
  AddResult result = AddResult::kAdded;
  if (!samples_.empty()) {
    const double newest = samples_.back().stamp_s;
    if (sample.stamp_s < newest - backwards_tolerance_s_) {
      samples_.clear();
      result = AddResult::kTimeWentBackwards;
    } else if (sample.stamp_s < newest) {
      return AddResult::kDroppedOutOfOrder;
    } else if (sample.stamp_s == newest) {
      samples_.back() = sample;
      return AddResult::kAdded;
    }
  }
  samples_.push_back(sample);
  while (samples_.size() > 2 && samples_.front().stamp_s < sample.stamp_s - length_s_) {
    samples_.pop_front();
  }
  return result;
}

Result<Eigen::Isometry3d> OdometryBuffer::poseAt(double t) const {
  using R = Result<Eigen::Isometry3d>;
  if (samples_.empty()) return R::failure("no odometry received");
  if (!std::isfinite(t)) return R::failure("odometry queried at a non-finite time");
  const OdometrySample& last = samples_.back();
  if (t >= last.stamp_s) {
    const double dt = t - last.stamp_s;
    if (dt > max_extrapolation_s_) {
      return R::failure("odometry ends " + std::to_string(dt) + " s before the queried time");
    }
    return R(last.odom_T_base *
             constantTwistMotion(BodyTwist{last.linear_mps, last.angular_radps}, dt));
  }
  if (t < samples_.front().stamp_s) return R::failure("odometry buffer starts after the time");
  auto it = std::lower_bound(samples_.begin(), samples_.end(), t,
                             [](const OdometrySample& s, double v) { return s.stamp_s < v; });
  const OdometrySample& b = *it;
  if (b.stamp_s == t || it == samples_.begin()) return R(b.odom_T_base);
  const OdometrySample& a = *(it - 1);
  const double u = (t - a.stamp_s) / (b.stamp_s - a.stamp_s);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = (1.0 - u) * a.odom_T_base.translation() + u * b.odom_T_base.translation();
  const Eigen::Quaterniond qa(a.odom_T_base.linear()), qb(b.odom_T_base.linear());
  out.linear() = qa.slerp(u, qb).toRotationMatrix();
  return R(out);
}

Result<BodyTwist> OdometryBuffer::twistAt(double t, double max_gap_s) const {
  using R = Result<BodyTwist>;
  if (samples_.empty()) return R::failure("no odometry received");
  const OdometrySample* best = nullptr;
  double best_gap = std::numeric_limits<double>::infinity();
  auto it = std::lower_bound(samples_.begin(), samples_.end(), t,
                             [](const OdometrySample& s, double v) { return s.stamp_s < v; });
  for (auto c : {it, it == samples_.begin() ? it : it - 1}) {
    if (c == samples_.end()) continue;
    const double gap = std::abs(c->stamp_s - t);
    if (gap < best_gap) best_gap = gap, best = &*c;
  }
  if (best == nullptr || !(best_gap <= max_gap_s)) {
    return R::failure("no odometry twist within " + std::to_string(max_gap_s) + " s");
  }
  return R(BodyTwist{best->linear_mps, best->angular_radps});
}

// ---- PriorTracker ---------------------------------------------------------------------------

const char* priorModeName(PriorMode mode) {
  switch (mode) {
    case PriorMode::kTracking:
      return "tracking";
    case PriorMode::kRelocalizing:
      return "relocalizing";
    case PriorMode::kLost:
      return "lost";
    default:
      return "no_prior";
  }
}

std::optional<PriorMode> priorModeFromName(const std::string& name) {
  for (PriorMode m :
       {PriorMode::kNoPrior, PriorMode::kTracking, PriorMode::kRelocalizing, PriorMode::kLost}) {
    if (name == priorModeName(m)) return m;
  }
  return std::nullopt;
}

void PriorTracker::setPosterior(const PosteriorEstimate& p) {
  if (!std::isfinite(p.stamp_s) || !p.map_T_base.matrix().allFinite() ||
      !p.covariance.allFinite()) {
    return;
  }
  // Keep the newest; a much older one comes from a restarted timeline (looping bag) and
  // replaces it.
  if (has_posterior_ && p.stamp_s < posterior_.stamp_s &&
      p.stamp_s > posterior_.stamp_s - options_.relocalization.max_posterior_age_s) {
    return;
  }
  posterior_ = p;
  has_posterior_ = true;
}

void PriorTracker::setExplicitPose(const Pose6& pose, double stamp_s, PriorSource source,
                                   bool z_known, const WindowExtent* window) {
  explicit_window_ = window != nullptr ? *window : WindowExtent();
  ++explicit_generation_;
  has_explicit_ = true;
  explicit_pose_ = pose;
  explicit_stamp_s_ = stamp_s;
  explicit_source_ = source;
  explicit_z_known_ = z_known;
  relocalizing_ = true;
  global_requested_ = false;  // a new pose to search around replaces a global request
  clearRejections();
}

Pose6 PriorTracker::completePlanarPose(const Pose6& planar, const OdometryBuffer* odometry,
                                       bool* z_known) const {
  Pose6 out = planar;
  bool known = false;
  if (has_posterior_) {
    const Pose6 p = fromIsometry(posterior_.map_T_base);
    out.roll = p.roll;
    out.pitch = p.pitch;
    if (std::hypot(p.x - planar.x, p.y - planar.y) <= 20.0) {
      out.z = p.z;
      known = true;
    }
  } else if (odometry != nullptr && !odometry->empty()) {
    const Pose6 o = fromIsometry(odometry->newest().odom_T_base);
    out.roll = o.roll;
    out.pitch = o.pitch;
  }
  if (z_known != nullptr) *z_known = known;
  return out;
}

Prior PriorTracker::carried(const Estimate& e, double ts, const OdometryBuffer* odometry) const {
  Prior prior;
  prior.age_s = ts - e.stamp_s;
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  bool by_odometry = false;
  if (odometry != nullptr && std::isfinite(e.stamp_s)) {
    const auto a = odometry->poseAt(e.stamp_s);
    const auto b = odometry->poseAt(ts);
    if (a.ok() && b.ok()) {
      motion = a->inverse() * b.value();  // base(te)_T_base(ts)
      by_odometry = true;
    }
  }
  if (!by_odometry && std::isfinite(e.stamp_s)) motion = constantTwistMotion(e.twist, prior.age_s);
  prior.pose = fromIsometry(e.map_T_base * motion);
  prior.covariance_xyh = e.covariance_xyh;
  prior.carried_by_odometry = by_odometry;
  return prior;
}

Prior PriorTracker::priorAt(double ts, const OdometryBuffer* odometry) const {
  const RelocalizationPolicyOptions& o = options_.relocalization;
  if (!std::isfinite(ts)) return Prior();
  if (has_explicit_) {
    const Estimate e{explicit_stamp_s_, toIsometry(explicit_pose_), Eigen::Matrix3d::Identity(),
                     BodyTwist()};
    Prior p = carried(e, ts, odometry);
    if (!std::isfinite(explicit_stamp_s_)) p.age_s = 0.0;
    const double s = options_.window.wide_half_xy_m / options_.window.sigma_multiplier;
    const double h = options_.window.wide_half_heading_rad / options_.window.sigma_multiplier;
    p.covariance_xyh = Eigen::Vector3d(s * s, s * s, h * h).asDiagonal();
    p.source = explicit_source_;
    p.wide = true;
    p.z_known = explicit_z_known_;
    p.wide_window = explicit_window_;
    p.explicit_generation = explicit_generation_;
    return widenIfLost(p);
  }
  // Ages are |scan - estimate|; an estimate from the future beyond the fresh limit (the other
  // timeline of a looping bag) is never used. After a jump, a posterior that disagrees with
  // the accepted matches has not fused them yet (or refused them): it is not used.
  const double inf = std::numeric_limits<double>::infinity();
  const bool posterior_trusted = has_posterior_ && !posteriorDisagrees(ts, odometry);
  const double posterior_age = posterior_trusted ? std::abs(ts - posterior_.stamp_s) : inf;
  const double match_age = has_match_ ? std::abs(ts - match_.stamp_s) : inf;
  const double stale_posterior_age =
      posterior_trusted && posterior_.stamp_s <= ts ? ts - posterior_.stamp_s : inf;
  const double stale_match_age = has_match_ && match_.stamp_s <= ts ? ts - match_.stamp_s : inf;
  Prior p;
  if (posterior_age <= o.max_posterior_age_s) {
    p = carried(Estimate{posterior_.stamp_s, posterior_.map_T_base,
                         planarCovariance(posterior_.covariance), posterior_.twist},
                ts, odometry);
    p.source = PriorSource::kEkf;
    p.wide = relocalizing_;
  } else if (match_age <= o.max_previous_match_age_s) {
    p = carried(match_, ts, odometry);
    const double grow_xy = o.previous_match_sigma_growth_mps * match_age;
    const double grow_h = 0.1 * match_age;
    p.covariance_xyh(0, 0) += grow_xy * grow_xy;
    p.covariance_xyh(1, 1) += grow_xy * grow_xy;
    p.covariance_xyh(2, 2) += grow_h * grow_h;
    p.source = PriorSource::kPreviousMatch;
    p.wide = relocalizing_;
  } else if (std::min(stale_posterior_age, stale_match_age) <= o.max_stale_prior_age_s) {
    // Stale: the newest past estimate centres the wide window, carried by odometry when it
    // covers the interval, else left where it was (a constant velocity over seconds is no
    // better than the wide window).
    const bool use_posterior = stale_posterior_age <= stale_match_age;
    Estimate e = use_posterior ? Estimate{posterior_.stamp_s, posterior_.map_T_base,
                                          planarCovariance(posterior_.covariance), BodyTwist()}
                               : match_;
    e.twist = BodyTwist();
    p = carried(e, ts, odometry);
    p.source = use_posterior ? PriorSource::kEkf : PriorSource::kPreviousMatch;
    p.wide = true;
  } else {
    return Prior();
  }
  return widenIfLost(p);
}

bool PriorTracker::posteriorDisagrees(double ts, const OdometryBuffer* odometry) const {
  if (!distrust_posterior_ || !has_match_ || !has_posterior_) return false;
  const Prior a = carried(Estimate{posterior_.stamp_s, posterior_.map_T_base,
                                   planarCovariance(posterior_.covariance), posterior_.twist},
                          ts, odometry);
  const Prior b = carried(match_, ts, odometry);
  return std::hypot(a.pose.x - b.pose.x, a.pose.y - b.pose.y) >
         options_.relocalization.jump_posterior_max_gap_m;
}

double PriorTracker::recentLogLikelihood() const {
  if (recent_ll_.empty()) return NAN;
  std::vector<double> v(recent_ll_.begin(), recent_ll_.end());
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

Prior PriorTracker::widenIfLost(Prior p) const {
  p.recent_log_likelihood_per_point = recentLogLikelihood();
  if (!lost()) return p;
  const WindowPolicyOptions& w = options_.window;
  p.lost = true;
  p.wide = true;
  const double half = globalHalfExtent(w, global_misses_);
  p.wide_window = WindowExtent{half, half, w.global_max_half_heading_rad};
  return p;
}

void PriorTracker::onAccepted(double stamp_s, const Pose6& pose,
                              const Eigen::Matrix3d& covariance_xyh, const Prior& used,
                              double log_likelihood_per_point) {
  has_match_ = true;
  // The reference of the likelihood-collapse rule: a jump (wide or global window) starts it
  // again, from the place the vehicle was found. Until a posterior agrees with the matches
  // again (a tracking match searched around it is accepted), the posterior is checked.
  if ((used.wide || used.lost) && !used.interim) {
    recent_ll_.clear();
    distrust_posterior_ = true;
  } else if (used.source == PriorSource::kEkf) {
    distrust_posterior_ = false;
  }
  if (std::isfinite(log_likelihood_per_point)) {
    recent_ll_.push_back(log_likelihood_per_point);
    const size_t keep = static_cast<size_t>(std::max(5, options_.acceptance.likelihood_history));
    while (recent_ll_.size() > keep) recent_ll_.pop_front();
  }
  match_ = Estimate{stamp_s, toIsometry(pose), covariance_xyh, BodyTwist()};
  if (has_posterior_) match_.twist = posterior_.twist;
  const double keep_s = options_.relocalization.match_history_s;
  if (keep_s > 0.0 && std::isfinite(stamp_s)) {
    history_.push_back(match_);
    // Bounded by time span and by count (10 Hz for keep_s), whatever the stamps do.
    const size_t cap = static_cast<size_t>(std::min(1e6, 10.0 * keep_s)) + 1;
    while (history_.size() > cap ||
           (!history_.empty() && history_.front().stamp_s < stamp_s - keep_s &&
            history_.front().stamp_s <= history_.back().stamp_s)) {
      history_.pop_front();
    }
  }
  clearRejections();
  // A match that started before the global search was asked for does not end it.
  if (used.lost) global_requested_ = false;
  if (has_explicit_ && used.explicit_generation != explicit_generation_) return;
  has_explicit_ = false;
  relocalizing_ = false;
}

void PriorTracker::onRejected(double stamp_s, const Prior& used, Rejection why) {
  // A search around a pose that a newer explicit pose replaced while it ran (a global search
  // takes seconds) says nothing about the new one: its rejection is not counted (else the new
  // pose's first global window would already be widened, its searches counted as misses).
  if (has_explicit_ && used.explicit_generation != explicit_generation_) return;
  ++consecutive_rejections_;
  collapses_ = why == Rejection::kLikelihoodCollapse ? collapses_ + 1 : 0;
  if (used.lost && !used.interim) {
    global_misses_ = global_misses_ < 1000000 ? global_misses_ + 1 : 0;
  }
  if (consecutive_rejections_ >= options_.relocalization.max_consecutive_rejections) {
    relocalizing_ = true;
  }
  if (used.wide && !used.lost) ++wide_rejections_;
  const RelocalizationPolicyOptions& o = options_.relocalization;
  if ((o.lost_after_rejections > 0 && consecutive_rejections_ >= o.lost_after_rejections) ||
      (o.lost_after_wide_rejections > 0 && wide_rejections_ >= o.lost_after_wide_rejections) ||
      (o.lost_after_collapses > 0 && collapses_ >= o.lost_after_collapses)) {
    lost_by_rejections_ = true;
  }
  // The pending explicit pose moves with the vehicle: from now on it is the pose this search
  // was centred on, at this scan's stamp (a configured pose, valid at any time until now, is
  // thereby taken as the pose of the first scan searched around it). Carried from there by
  // odometry, its offset from the truth stays what it was when it was given, however long
  // the searches around it take and however short the odometry buffer is.
  if (has_explicit_ && used.explicit_generation == explicit_generation_ && std::isfinite(stamp_s) &&
      (used.carried_by_odometry || !std::isfinite(explicit_stamp_s_))) {
    explicit_pose_ = used.pose;
    explicit_stamp_s_ = stamp_s;
  }
}

bool PriorTracker::recallAt(double stamp_s) {
  const double gap = options_.relocalization.recall_max_gap_s;
  if (!std::isfinite(stamp_s) || history_.empty() || !(gap > 0.0)) return false;
  const Estimate* best = nullptr;
  for (const Estimate& e : history_) {
    const double d = std::abs(e.stamp_s - stamp_s);
    if (d <= gap && (best == nullptr || d < std::abs(best->stamp_s - stamp_s))) best = &e;
  }
  if (best == nullptr) return false;
  const Estimate e = *best;
  setExplicitPose(fromIsometry(e.map_T_base), e.stamp_s, PriorSource::kPreviousMatch, true);
  return true;
}

void PriorTracker::reset() {
  has_posterior_ = false;
  has_match_ = false;
  has_explicit_ = false;
  relocalizing_ = false;
  global_requested_ = false;
  clearRejections();
  recent_ll_.clear();
  distrust_posterior_ = false;
}

void PriorTracker::clearRejections() {
  consecutive_rejections_ = 0;
  wide_rejections_ = 0;
  collapses_ = 0;
  global_misses_ = 0;
  lost_by_rejections_ = false;
}

bool PriorTracker::lost() const { return global_requested_ || lostByRejections(); }

bool PriorTracker::lostByRejections() const { return lost_by_rejections_; }

PriorMode PriorTracker::mode() const {
  const bool has_prior = has_explicit_ || has_posterior_ || has_match_;
  if (has_prior && lost()) return PriorMode::kLost;
  if (has_explicit_ || (relocalizing_ && (has_posterior_ || has_match_))) {
    return PriorMode::kRelocalizing;
  }
  if (has_posterior_ || has_match_) return PriorMode::kTracking;
  return PriorMode::kNoPrior;
}

}  // namespace gmm_localization
