#pragma once
// Prior selection for the scan matcher (paper V-B: matches "initialized around our 3-sigma
// posterior belief") and the relocalization state machine. ROS-free; used unchanged by the
// matcher nodelet and by LocalizerPipeline.
//
// OdometryBuffer keeps recent INS samples (odom_T_base and body twist) so that an estimate
// made at one time can be carried to a scan's stamp: map_T_base(ts) = map_T_base(te) *
// odom_T_base(te)^-1 * odom_T_base(ts) (the map->odom correction is taken as constant over
// the short interval; odometry drift over it is far below a cell).
//
// PriorTracker states (mode()):
//   kNoPrior       nothing known: no search ("no prior" status).
//   kTracking      window = clamp(sigma_multiplier x sigma) of the EKF posterior carried to the
//                  scan stamp (or, without a fresh posterior, of the last accepted match with a
//                  sigma growing with its age).
//   kRelocalizing  the wide window (WindowPolicyOptions::wide_*), centred on the explicit pose
//                  while one is pending (carried by odometry from the last scan searched around
//                  it, onRejected), else on the tracking centre.
//   kLost          the global window (WindowPolicyOptions::global_max_*) around the same centre,
//                  widened after each global search that found nothing (globalHalfExtent).
// Transitions:
//   setExplicitPose (/initialpose, configured pose)           -> kRelocalizing around it
//   requestRelocalization (relocalize service)                -> kRelocalizing
//   max_consecutive_rejections rejected matches in a row      -> kRelocalizing
//   lost_after_rejections rejected in a row, or lost_after_wide_rejections rejected wide
//   windows in a row, or lost_after_collapses likelihood collapses in a row, or
//   requestRelocalization(true)                               -> kLost (global window), kept
//                                                                whatever the next rejections
//                                                                are, until one of these two:
//   setExplicitPose                                           -> kRelocalizing
//   onAccepted                                                -> kTracking (explicit pose done,
//                                                                unless a newer one is pending)
//   reset (time went backwards)                               -> kNoPrior
// EKF gate lockout is not seen here: the filter (LocalizationFilter) inflates its covariance,
// so the next posterior's 3 sigma reaches the maximum window by itself.
// An estimate older than the fresh limits but within max_stale_prior_age_s still centres a wide
// window (e.g. after the EKF reset on a time jump); beyond that there is no prior.

#include <deque>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/localization/match_policy.h"

namespace gmm_localization {

/// One INS odometry sample.
struct OdometrySample {
  double stamp_s = 0.0;                                           ///< [s]
  Eigen::Isometry3d odom_T_base = Eigen::Isometry3d::Identity();  ///< base_link in odom
  Eigen::Vector3d linear_mps = Eigen::Vector3d::Zero();           ///< body twist [m/s]
  Eigen::Vector3d angular_radps = Eigen::Vector3d::Zero();        ///< body rates [rad/s]
};

/// Body twist of base_link (for deskewing).
struct BodyTwist {
  Eigen::Vector3d linear_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_radps = Eigen::Vector3d::Zero();
};

class OdometryBuffer {
 public:
  enum class AddResult {
    kAdded,
    kDroppedOutOfOrder,  ///< slightly older than the newest sample (or not finite): ignored
    kTimeWentBackwards,  ///< older by more than backwards_tolerance_s: buffer restarted
  };

  /// Keeps length_s [s] of samples; poses may be extrapolated max_extrapolation_s [s] past the
  /// newest sample with its twist.
  explicit OdometryBuffer(double length_s = 10.0, double max_extrapolation_s = 0.3,
                          double backwards_tolerance_s = 1.0)
      : length_s_(length_s),
        max_extrapolation_s_(max_extrapolation_s),
        backwards_tolerance_s_(backwards_tolerance_s) {}

  AddResult add(const OdometrySample& sample);
  void clear() { samples_.clear(); }
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  /// Newest sample; only when !empty().
  const OdometrySample& newest() const { return samples_.back(); }

  /// odom_T_base at t [s]: interpolated between the neighbouring samples (linear translation,
  /// slerp rotation), or extrapolated with the newest twist up to max_extrapolation_s. Fails
  /// outside that span.
  Result<Eigen::Isometry3d> poseAt(double t) const;
  /// Twist of the sample nearest to t, when within max_gap_s [s].
  Result<BodyTwist> twistAt(double t, double max_gap_s) const;

 private:
  double length_s_, max_extrapolation_s_, backwards_tolerance_s_;
  std::deque<OdometrySample> samples_;
};

/// The EKF's published estimate (nav_msgs/Odometry on `odometry`, or Ekf::stateAt).
struct PosteriorEstimate {
  double stamp_s = 0.0;
  Eigen::Isometry3d map_T_base = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();  ///< (x, y, z, roll, pitch, yaw)
  BodyTwist twist;
};

enum class PriorMode { kNoPrior, kTracking, kRelocalizing, kLost };

/// Why a search that ran was not accepted, as far as the prior tracker cares.
enum class Rejection {
  kOther,               ///< any reason but the one below
  kLikelihoodCollapse,  ///< the likelihood-collapse rule (counts towards lost_after_collapses)
};
/// "no_prior", "tracking", "relocalizing", "lost"
const char* priorModeName(PriorMode mode);
/// The mode of a priorModeName() text; none for any other text.
std::optional<PriorMode> priorModeFromName(const std::string& name);

/// Not thread-safe (the matcher guards it with its state mutex).
class PriorTracker {
 public:
  explicit PriorTracker(const LocalizationPolicyOptions& options) : options_(options) {}

  /// Latest EKF posterior (keeps the newest by stamp).
  void setPosterior(const PosteriorEstimate& posterior);
  /// A pose to search around with the wide window until a match is accepted. stamp_s: the
  /// pose's time (carried by odometry to each scan); NaN: the pose at the first scan searched
  /// around it (carried from there on, onRejected).
  /// window: its own wide window (null: WindowPolicyOptions::wide_*).
  void setExplicitPose(const Pose6& pose, double stamp_s, PriorSource source, bool z_known,
                       const WindowExtent* window = nullptr);
  /// Completes a planar pose (x, y, yaw; e.g. rviz's "2D Pose Estimate") with z, roll and pitch
  /// from the posterior when one is known (z counts as known only within 20 m of it), else
  /// roll and pitch from the newest odometry orientation (the odom frame is level) and z = the
  /// given one, unknown.
  Pose6 completePlanarPose(const Pose6& planar, const OdometryBuffer* odometry,
                           bool* z_known) const;
  /// Search the wide window until a match is accepted; `global`: the global window
  /// (WindowPolicyOptions::global_max_*, as when lost) around the prior, from the next scan.
  void requestRelocalization(bool global = false) {
    relocalizing_ = true;
    global_requested_ = global_requested_ || global;
  }

  /// The prior for a scan stamped scan_stamp_s; odometry may be null (then estimates are carried
  /// with their own twist at constant velocity).
  Prior priorAt(double scan_stamp_s, const OdometryBuffer* odometry) const;

  /// A published match (stamp, pose, published (x, y, yaw) covariance) searched around `used`.
  /// It ends relocalization, unless an explicit pose newer than `used` is pending (a match that
  /// started before /initialpose does not cancel it).
  /// log_likelihood_per_point: the match's (MatchResult), kept for
  /// Prior::recent_log_likelihood_per_point (NaN: not kept).
  void onAccepted(double stamp_s, const Pose6& pose, const Eigen::Matrix3d& covariance_xyh,
                  const Prior& used, double log_likelihood_per_point = NAN);
  /// A search of the scan stamped stamp_s, around `used`, that ran but was not accepted (input
  /// problems and "no prior" do not count). A pending explicit pose that `used` came from is
  /// re-anchored at stamp_s to the pose `used` carried it to (when carried by odometry, or when
  /// it had no stamp): the explicit pose follows the vehicle's odometry while it is searched.
  /// A rejected global search (used.lost, not interim) widens the next global window
  /// (globalHalfExtent). A search around an explicit pose replaced since (another
  /// generation) is not counted at all.
  void onRejected(double stamp_s, const Prior& used, Rejection why = Rejection::kOther);
  /// Forgets everything (time went backwards) except the match history.
  void reset();
  /// After a reset: when an accepted match of the history lies within
  /// RelocalizationPolicyOptions::recall_max_gap_s of stamp_s, searches the wide window around
  /// it (an explicit pose of source previous_match, valid at its own stamp) and returns true.
  bool recallAt(double stamp_s);
  size_t historySize() const { return history_.size(); }

  PriorMode mode() const;
  /// RelocalizationPolicyOptions::lost_after_rejections rejected matches in a row, or
  /// lost_after_wide_rejections rejected matches of a wide window in a row, or a global search
  /// requested (requestRelocalization(true)); until a match is accepted.
  bool lost() const;
  /// lost() by the rejections (not only by a global search asked for): the estimate itself is
  /// not trusted. Once reached it holds until a match is accepted or a pose is given (a
  /// rejection of another kind does not undo the likelihood collapses that made it lost).
  bool lostByRejections() const;
  int consecutiveRejections() const { return consecutive_rejections_; }
  /// Global searches rejected since the last accepted match or given pose (globalHalfExtent).
  int globalMisses() const { return global_misses_; }
  bool hasPosterior() const { return has_posterior_; }
  const LocalizationPolicyOptions& options() const { return options_; }
  const PosteriorEstimate& posterior() const { return posterior_; }

 private:
  struct Estimate {
    double stamp_s;
    Eigen::Isometry3d map_T_base;
    Eigen::Matrix3d covariance_xyh;
    BodyTwist twist;
  };
  Prior carried(const Estimate& e, double scan_stamp_s, const OdometryBuffer* odometry) const;
  /// The global window when lost() (Prior::lost).
  /// Also sets the prior's recent_log_likelihood_per_point.
  Prior widenIfLost(Prior p) const;
  /// Median of recent_ll_ (NaN: none).
  double recentLogLikelihood() const;
  /// Forgets the rejections in a row, the global misses and the lost state they led to (a
  /// match accepted, a pose given, a reset).
  void clearRejections();
  /// After a jump (distrust_posterior_): the posterior carried to ts lies farther than
  /// jump_posterior_max_gap_m from the last accepted match carried to ts.
  bool posteriorDisagrees(double ts, const OdometryBuffer* odometry) const;

  LocalizationPolicyOptions options_;
  bool has_posterior_ = false;
  PosteriorEstimate posterior_;
  bool has_match_ = false;
  Estimate match_{};
  std::deque<Estimate> history_;  ///< accepted matches, in arrival order
  bool has_explicit_ = false;
  Pose6 explicit_pose_;
  double explicit_stamp_s_ = 0.0;
  PriorSource explicit_source_ = PriorSource::kInitialPose;
  bool explicit_z_known_ = false;
  uint64_t explicit_generation_ = 0;
  WindowExtent explicit_window_;
  bool relocalizing_ = false;
  bool global_requested_ = false;
  int consecutive_rejections_ = 0;
  int wide_rejections_ = 0;          ///< rejected in a row with a wide (not global) window
  int collapses_ = 0;                ///< rejected in a row by the likelihood-collapse rule
  int global_misses_ = 0;            ///< see globalMisses()
  bool lost_by_rejections_ = false;  ///< see lostByRejections()
  std::deque<double> recent_ll_;     ///< log-likelihoods per point of the recent accepted matches
  bool distrust_posterior_ = false;  ///< a jump accepted, no tracking match from the EKF since
};

}  // namespace gmm_localization
