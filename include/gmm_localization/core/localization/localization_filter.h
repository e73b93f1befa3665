#pragma once
// LocalizationFilter: the core Ekf plus the policy around it that the ekf nodelet and
// LocalizerPipeline share, so that both fuse the same way:
// - default covariances for inputs that report none (all zeros, the ROS convention);
// - initialization from /initialpose or, when nothing else started the filter, from the first
//   scan match (with the match's own covariance);
// - /initialpose: the pose's x, y, yaw variances are raised to at least the relocalization
//   sigmas (the matcher searches its wide window around such a pose, so a correction across
//   that window must pass the Mahalanobis gate); a planar pose (z unknown) keeps the filter's
//   z, roll and pitch when it runs, else gets unknown_*_sigma;
// - relocalization: relocalize() and the gate lockout (gate_lockout_count consecutive
//   matches rejected by the Mahalanobis gate) inflate the x, y, yaw covariance to the
//   relocalization sigmas. The matcher then sees a 3-sigma beyond its maximum window in the
//   posterior and searches the maximum window; the next match passes the gate and collapses
//   the covariance again (paper V-B: matches "initialized around our 3-sigma posterior").
// - the matcher's mode (onMatcherMode, from each MatchStatus): when it no longer confirms the
//   estimate (relocalizing: rejected matches in a row; lost: the global window next) the x, y,
//   yaw covariance is raised to at least the relocalization or the lost sigmas, so that the
//   published covariance covers a vehicle that is not where the filter thinks (a kidnap, a
//   stale start) and the match that relocalizes it passes the Mahalanobis gate.
// - time going backwards (a looping bag: Ekf reports kTimeWentBackwards) or
//   forward_jump_reset_count consecutive forward jumps: the filter stops (inactive) and waits
//   for a new initial pose or match. Counters survive (they live in the Ekf).
// ROS-free; not thread-safe (one caller thread or a lock).

#include <array>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/filter/ekf.h"
#include "gmm_localization/core/localization/gnss_position.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {

/// Covariances given to inputs whose covariance is all zeros ("unknown"), standard deviations.
struct MeasurementDefaults {
  double imu_orientation_sigma_rad = 0.01;
  double imu_angular_velocity_sigma_radps = 0.01;
  double imu_linear_acceleration_sigma_mps2 = 0.2;
  double twist_linear_sigma_mps = 0.05;
  double twist_angular_sigma_radps = 0.01;

  std::string validate() const;
};

struct FilterPolicyOptions {
  /// Components of a scan-match pose that are fused, order (x, y, z, roll, pitch, yaw). Roll
  /// and pitch are better observed by the IMU; the matcher's come from a short hill climb.
  std::array<bool, 6> match_mask = {true, true, true, false, false, true};
  /// Start the filter from the first scan match when no initial pose came.
  bool initialize_from_match = true;
  /// Consecutive gate-rejected matches that trigger the inflation (relocalization).
  int gate_lockout_count = 5;
  /// x, y and yaw standard deviations after relocalize() or a lockout, and the floor of an
  /// initial pose's [m], [rad]. With the matcher's sigma_multiplier 3 and maximum window
  /// 12.5 m / 15 deg, anything above 4.2 m / 0.087 rad searches the maximum window.
  double relocalize_sigma_xy_m = 6.0;
  double relocalize_sigma_yaw_rad = 0.13;
  /// An initial pose whose heading sigma exceeds this does not start a filter that is not
  /// running (with initialize_from_match): its heading is unknown, so dead-reckoning the INS
  /// from it would publish a pose moving in an unknown direction; the first accepted match
  /// starts the filter instead (kStartDeferred). 0.52 rad: the heading 3 sigma of 90 deg from
  /// which the matcher searches the full turn. A running filter still takes such a pose.
  double max_start_sigma_yaw_rad = 0.52;
  /// x, y and yaw standard deviations while the matcher is lost [m], [rad]: at least the global
  /// window (the matcher's window/global_max_half_xy_m, 50 m, as 3 sigma); yaw: a full turn is
  /// beyond a Gaussian, 1.05 rad puts a 90 deg error at 1.5 sigma.
  double lost_sigma_xy_m = 17.0;
  double lost_sigma_yaw_rad = 1.05;
  /// Standard deviations of a planar initial pose's unknown z and roll/pitch [m], [rad].
  double unknown_z_sigma_m = 3.0;
  double unknown_tilt_sigma_rad = 0.05;
  /// Consecutive kTimeJumpedForward reports after which the filter stops and waits.
  int forward_jump_reset_count = 3;
  MeasurementDefaults defaults;
  /// Floor of the INS linear-twist standard deviation, per axis k: sqrt(min^2 + (per_speed *
  /// v_k)^2), v_k the twist's own speed along k. An INS reports millimetres per second but carries
  /// a scale error of a few tenths of a percent; trusted as reported, the filter integrates that
  /// bias between matches and runs ahead of them at speed. 0, 0: the reported covariance as is.
  /// The scale error itself is estimated by the EKF (EkfOptions::estimate_twist_scale); the
  /// floor covers the time before that estimate has converged.
  double twist_linear_min_sigma_mps = 0.0;
  double twist_linear_sigma_per_speed = 0.0;
  /// GNSS fixes as x, y (z) position measurements (addGnss; gnss_position.h), gated with
  /// EkfOptions::gnss_gate_probability. Off by default: the paper's EKF fuses only the IMU and
  /// the scan matches; its reflectivity baseline in snow ran "with GPS".
  bool gnss_enabled = false;
  GnssPositionOptions gnss;

  std::string validate() const;
};

enum class FilterEventKind {
  kInitializedFromPose,   ///< /initialpose (re)started or moved the filter
  kInitializedFromMatch,  ///< first match started the filter
  kStoppedTimeBackwards,  ///< waiting for a new initial pose or match
  kStoppedTimeJump,
  kGateLockout,          ///< covariance inflated after consecutive gate rejections
  kRelocalizeRequest,    ///< covariance inflated on request
  kMatcherRelocalizing,  ///< covariance inflated: the matcher no longer confirms the estimate
  kMatcherLost,          ///< covariance inflated to the lost sigmas: the matcher is lost
  kStartDeferred,        ///< an initial pose without a heading: the first match starts it
};
const char* filterEventName(FilterEventKind kind);

struct FilterEvent {
  FilterEventKind kind;
  double stamp_s = 0.0;
  std::string detail;
};

class LocalizationFilter {
 public:
  static Result<LocalizationFilter> create(const EkfOptions& ekf,
                                           const FilterPolicyOptions& policy);

  /// IMU sample in base_link; zero covariances get the defaults. Empty when inactive; the
  /// samples of the last pendingSpanS() are then kept and replayed after the stamp of the pose
  /// that starts the filter (a scan match arrives a few hundred ms after its stamp, a global
  /// search's seconds after: without the replay the first estimate would stay where the
  /// vehicle was then).
  std::vector<FuseReport> addImu(ImuMeasurement imu);
  /// INS body twist; a zero covariance gets the defaults. Kept like IMU samples while inactive.
  FuseReport addTwist(TwistMeasurement twist);

  /// How much IMU and twist history is kept while the filter waits for its first pose [s]:
  /// the Ekf's history_length_s, the oldest a match may be and still be fused when running.
  double pendingSpanS() const { return ekf_.options().history_length_s; }
  /// A first match stamped more than this before the oldest kept IMU or twist sample does not
  /// start the filter (the motion since its scan is unknown): the ekf nodelet's default
  /// imu_timeout_s, an input silent that long is a dropout [s].
  static constexpr double kMotionGapS = 0.5;
  /// The map's georeference, which places GNSS fixes in the map frame.
  void setGeoreference(const Georeference& georeference) { georeference_ = georeference; }
  /// The GNSS antenna in base_link (the ekf nodelet's TF), removed with the filter's heading.
  void setGnssLeverArm(const Eigen::Vector3d& antenna_in_base) {
    options_.gnss.antenna_in_base = antenna_in_base;
  }
  /// A GNSS fix (options().gnss_enabled): fused as base_link's position with the filter's
  /// heading for the lever arm. Refused (kRejectedInvalid, with the reason, counted in
  /// gnssRefused()) when the input is disabled, the fix has no solution or does not place in
  /// the map; kRejectedNotInitialized while the filter is not running (a fix does not start it:
  /// it has no heading; the GNSS initializer gives the first pose).
  FuseReport addGnss(const GnssFix& fix);
  uint64_t gnssRefused() const { return gnss_refused_; }

  /// Scan match at stamp_s: pose of base_link in map with its 6x6 covariance (x, y, z, roll,
  /// pitch, yaw), fused with match_mask (or starting the filter, see the file comment, and
  /// then replaying the kept IMU and twist since stamp_s; a match older than those samples
  /// reach is refused as kRejectedTooOld with the reason).
  FuseReport addMatch(double stamp_s, const Pose6& pose, const Matrix6d& covariance);
  /// /initialpose. z_and_tilt_known false: z, roll, pitch are taken from the running filter (or
  /// get the unknown sigmas). Fails, changing nothing, on a non-finite pose or bad covariance.
  Status setInitialPose(const Pose6& pose, const Matrix6d& covariance, double stamp_s,
                        bool z_and_tilt_known);
  /// Inflates x, y, yaw to the relocalization sigmas; fails when the filter is not running.
  Status relocalize(double stamp_s);
  /// The matcher's prior mode after a scan stamped stamp_s (MatchReport::mode_after, the
  /// status's prior_mode): kRelocalizing raises x, y, yaw to at least the relocalization sigmas,
  /// kLost to at least the lost sigmas (an event on each entry into either mode); other modes
  /// change nothing. The floor goes into the filter's history at stamp_s
  /// (Ekf::raiseCovarianceAt), so matches are fused before or after it by their stamps, however
  /// late they come. Nothing happens while the filter is inactive.
  void onMatcherMode(double stamp_s, PriorMode mode);
  /// Stops the filter (waits for an initial pose or a match).
  void stop();

  /// Running: initialized and not stopped. Publish nothing while false.
  bool active() const { return active_; }
  /// State at time_s (see Ekf::stateAt); fails when inactive.
  Result<EkfState> stateAt(double time_s) const;
  const Ekf& ekf() const { return ekf_; }
  const FilterPolicyOptions& options() const { return options_; }
  int consecutiveGateRejections() const { return gate_run_; }
  uint64_t lockouts() const { return lockouts_; }
  uint64_t stops() const { return stops_; }
  /// Events since the last call (for logs and diagnostics), oldest first.
  std::vector<FilterEvent> takeEvents();

 private:
  LocalizationFilter(Ekf ekf, const FilterPolicyOptions& options)
      : ekf_(std::move(ekf)), options_(options) {}
  void checkTime(const FuseReport& report);
  Status inflate(FilterEventKind kind, double stamp_s, std::string detail);
  void event(FilterEventKind kind, double stamp_s, std::string detail);
  /// Why a filter started at stamp_s could not replay the motion since (empty: it can).
  std::string motionGapAfter(double stamp_s) const;
  /// Feeds the kept IMU and twist samples stamped after stamp_s, in time order, then drops all.
  void replayPending(double stamp_s);

  Ekf ekf_;
  std::deque<ImuMeasurement> pending_imu_;
  std::deque<TwistMeasurement> pending_twist_;
  FilterPolicyOptions options_;
  bool active_ = false;
  int gate_run_ = 0;
  PriorMode matcher_mode_ = PriorMode::kNoPrior;  ///< of the newest status (onMatcherMode)
  double last_status_s_ = -std::numeric_limits<double>::infinity();  ///< its stamp
  int forward_jumps_ = 0;
  uint64_t lockouts_ = 0;
  uint64_t stops_ = 0;
  Georeference georeference_;
  uint64_t gnss_refused_ = 0;
  std::vector<FilterEvent> events_;
};

}  // namespace gmm_localization
