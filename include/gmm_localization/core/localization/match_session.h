#pragma once
// MatchSession: the matcher's session rules, ROS-free, shared by the matcher nodelet
// (ros/matcher.h, on its subscriber and worker threads) and by LocalizerPipeline (the offline
// model `evaluate` runs on a virtual clock), so that both follow literally the same rules:
//
// - State: the PriorTracker, the OdometryBuffer (INS history), the configured pose and an
//   epoch.
// - Time: a scan stamped earlier than the previous scan by more than time_backwards_tolerance_s
//   (a looping bag) resets the tracker, increments the epoch, drops every waiting scan (counted)
//   and, when configured_pose_on_reset, arms the configured pose again. Before that, a scan
//   stamped more than max_scan_ahead_s after the clock or more than max_scan_age_s before it is
//   refused with a reason and changes nothing: one bad stamp neither resets the session nor
//   makes the next good scan look like time going backwards. "After the clock" means after
//   both the clock and the newest INS sample: on a loaded host /clock arrives late.
// - Queue: scans wait in arrival order in a DropOldestQueue of scan_queue_size entries; a scan
//   arriving at a full queue drops the oldest. Drops are counted in total and since the last
//   scan taken (the count the next status or report carries). The scan being matched is not in
//   the queue.
// - Start: a match starts from beginMatch(): the tracker's prior at the scan stamp (carried by
//   odometry), the deskew twist (deskewTwist(), when deskew) and the current epoch.
// - Outcome: finishMatch() applies the result of a match begun with that epoch: begun in an
//   older epoch -> discarded (outcome skipped, reason "discarded: time went backwards during the
//   match"); accepted -> PriorTracker::onAccepted with the (x, y, yaw) block of the published
//   covariance; rejected -> PriorTracker::onRejected; skipped -> nothing. The report's
//   mode_after is then the tracker's mode.
//
// MatchSession<Item> queues Items (the nodelet: the received clouds, converted in its worker;
// LocalizerPipeline: the scan with its arrival time and latency). The rules that do not depend
// on the item type are in MatchSessionState (match_session.cpp).
//
// Thread-safety: not synchronised (like PriorTracker and DropOldestQueue): the owner serialises
// every call. The matcher nodelet holds its session mutex around each call; the match itself
// (MatchProcessor::process) runs outside it, between beginMatch() and finishMatch().

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

#include "gmm_localization/core/common/drop_oldest_queue.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/localization/match_policy.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {

/// The session options (the matcher nodelet's parameters of the same names, config/matcher.yaml;
/// configured_pose_on_reset is initial_pose/on_reset).
struct MatchSessionOptions {
  double odometry_buffer_s = 10.0;            ///< INS history kept [s]
  double odometry_max_extrapolation_s = 0.3;  ///< [s] past the newest INS sample
  bool deskew = true;                         ///< motion-compensate scans with the INS twist
  double deskew_twist_max_gap_s = 0.2;        ///< INS sample within this of mid-scan [s]
  double time_backwards_tolerance_s = 1.0;    ///< scan stamp regression that resets [s]
  double max_scan_ahead_s = 2.0;              ///< stamp after clock and INS: refused beyond [s]
  double max_scan_age_s = 10.0;               ///< stamp before the clock: refused beyond [s]
  bool configured_pose_on_reset = true;       ///< re-arm the configured pose after a reset
  /// Scans waiting while one is matched, in arrival order; when full the oldest is dropped
  /// (1: only the latest waits, the behaviour of a queue_size 1 subscriber).
  int scan_queue_size = 3;

  /// Empty when valid, else the first offending key with its value and range (the nodelet
  /// loader's ranges).
  std::string validate() const;
};

/// The twist used to deskew a scan: the INS sample nearest to the middle of the revolution
/// (stamp + half the largest point time) within max_gap_s; else the posterior's twist when the
/// tracker holds one within max_gap_s of the stamp; else none.
std::optional<BodyTwist> deskewTwist(const ScanInput& scan, const OdometryBuffer& odometry,
                                     const PriorTracker& tracker, double max_gap_s);

/// What a scan's match starts from (MatchSessionState::beginMatch).
struct MatchStart {
  Prior prior;
  std::optional<BodyTwist> twist;  ///< for deskewing; none: not deskewed
  uint64_t epoch = 0;              ///< give it back to finishMatch()
  /// Not to be searched, and why (answered as skipped): the localization is lost by its
  /// rejections and the global search of an earlier scan is running; a search around the
  /// estimate would only take the cores from it. Empty: search.
  std::string skip_reason;
  const BodyTwist* twistOrNull() const { return twist ? &*twist : nullptr; }
  /// A global search (a lost prior, not skipped): the global worker's.
  bool global() const { return skip_reason.empty() && prior.lost; }
};

/// The session rules that do not depend on the queued item type (see the file comment).
class MatchSessionState {
 public:
  /// Options must be valid (validate()); policy: the tracker's.
  MatchSessionState(const MatchSessionOptions& options, const LocalizationPolicyOptions& policy);

  const MatchSessionOptions& options() const { return options_; }

  /// INS odometry (OdometryBuffer::add).
  OdometryBuffer::AddResult addOdometry(const OdometrySample& sample);
  /// The EKF posterior (PriorTracker::setPosterior: keeps the newest, ignores non-finite).
  void setPosterior(const PosteriorEstimate& posterior);
  /// The configured initial pose: armed now (searched with `window`, null: the policy's wide
  /// window; taken as the pose of the next scan, then carried by odometry while rejected) and
  /// again after each reset when configured_pose_on_reset.
  void setConfiguredPose(const Pose6& pose, bool z_known, const WindowExtent* window = nullptr);
  /// An initial pose (/initialpose) at stamp_s (NaN: the pose at the first scan searched around
  /// it). z_known false: a planar pose, completed with z, roll and pitch
  /// (PriorTracker::completePlanarPose). Returns the pose searched around; *searched_z_known:
  /// whether its height is known. covariance_xyh, when given, widens the search for a coarse pose
  /// (explicitPoseWindow); *window_out, when given, receives the window searched.
  Pose6 setInitialPose(const Pose6& pose, double stamp_s, bool z_known,
                       bool* searched_z_known = nullptr,
                       const Eigen::Matrix3d* covariance_xyh = nullptr,
                       WindowExtent* window_out = nullptr);

  /// The global search from the next scan on (the matcher's global_localization service): the
  /// global window (WindowPolicyOptions::global_max_*) around the current prior until a match
  /// is accepted. Empty when armed, else why not (no pose to search around).
  std::string requestGlobalSearch();

  /// The prior, deskew twist and epoch for this scan's match.
  /// global_available false: a global search of an earlier scan is still running, so a lost
  /// prior becomes an interim one (Prior::interim) instead of a second global search when the
  /// loss was asked for (global_localization: the estimate was fine), else the scan is skipped
  /// (skip_reason).
  MatchStart beginMatch(const ScanInput& scan, bool global_available = true) const;
  /// The deskew twist for this scan (none when deskew is off or no twist is known).
  std::optional<BodyTwist> deskewTwistFor(const ScanInput& scan) const;
  /// Applies the outcome of a match begun in `epoch` (see the file comment). Returns false when
  /// the report was discarded (it is then a skipped report with the reason set).
  bool finishMatch(uint64_t epoch, MatchReport* report);

  const PriorTracker& tracker() const { return tracker_; }
  const OdometryBuffer& odometry() const { return odometry_; }
  uint64_t epoch() const { return epoch_; }
  uint64_t resets() const { return resets_; }  ///< times time went backwards
  /// Resets after which the search restarted around a remembered match of the same stamp
  /// (PriorTracker::recallAt); lastResetRecalled(): whether the latest reset did.
  uint64_t recalls() const { return recalls_; }
  bool lastResetRecalled() const { return last_reset_recalled_; }

 protected:
  /// The time rule for a scan stamped stamp_s: returns how far time went backwards [s] (> 0:
  /// the session was reset and the caller drops the waiting scans), else 0.
  double checkScanStamp(double stamp_s);
  /// Why a scan stamped stamp_s is refused at clock_s (max_scan_ahead_s, max_scan_age_s; a
  /// non-finite stamp), "" when it is not or clock_s is NaN.
  std::string stampVersusClock(double stamp_s, double clock_s) const;

 private:
  void armConfiguredPose();

  MatchSessionOptions options_;
  WindowPolicyOptions window_policy_;
  PriorTracker tracker_;
  OdometryBuffer odometry_;
  uint64_t epoch_ = 0;
  uint64_t resets_ = 0;
  uint64_t recalls_ = 0;
  bool last_reset_recalled_ = false;
  bool have_last_scan_ = false;
  double last_scan_stamp_s_ = 0.0;
  std::optional<Pose6> configured_pose_;
  bool configured_z_known_ = true;
  std::optional<WindowExtent> configured_window_;
};

/// The session with its scan queue of Items.
template <typename Item>
class MatchSession : public MatchSessionState {
 public:
  /// A scan's arrival (onScanArrival).
  struct Arrival {
    double backwards_jump_s = 0.0;  ///< > 0: time went backwards by this; the session was reset
    size_t dropped = 0;             ///< waiting scans of the old timeline dropped by the reset
    std::string refused;            ///< non-empty: the stamp is refused (why); do not enqueue
    bool timeWentBackwards() const { return backwards_jump_s > 0.0; }
  };
  /// The oldest waiting scan (takeNext).
  struct Next {
    Item item;
    uint32_t dropped_before = 0;  ///< scans dropped since the previous takeNext()
  };

  MatchSession(const MatchSessionOptions& options, const LocalizationPolicyOptions& policy)
      : MatchSessionState(options, policy),
        waiting_(static_cast<size_t>(std::max(1, options.scan_queue_size))) {}

  /// Call when a scan stamped stamp_s arrives at clock_s (NaN: no clock check), before
  /// enqueue(): a stamp too far from the clock is refused (Arrival::refused, nothing changes);
  /// else the time rule; after a reset the waiting scans are dropped (counted).
  Arrival onScanArrival(double stamp_s, double clock_s = NAN) {
    Arrival a;
    a.refused = stampVersusClock(stamp_s, clock_s);
    if (!a.refused.empty()) return a;
    a.backwards_jump_s = checkScanStamp(stamp_s);
    if (a.timeWentBackwards()) a.dropped = count(waiting_.clear());
    return a;
  }
  /// Queues a scan; returns how many of the oldest were dropped to make room.
  size_t enqueue(Item item) { return count(waiting_.push(std::move(item))); }
  /// onScanArrival() then, unless refused, enqueue(); Arrival::dropped counts both.
  Arrival arrive(double stamp_s, Item item, double clock_s = NAN) {
    Arrival a = onScanArrival(stamp_s, clock_s);
    if (a.refused.empty()) a.dropped += enqueue(std::move(item));
    return a;
  }

  bool hasWaiting() const { return !waiting_.empty(); }
  size_t waiting() const { return waiting_.size(); }
  size_t queueCapacity() const { return waiting_.capacity(); }
  /// Removes the oldest waiting scan, with the drops since the previous one. Precondition:
  /// hasWaiting().
  Next takeNext() {
    Next n{waiting_.pop(), dropped_since_taken_};
    dropped_since_taken_ = 0;
    return n;
  }
  uint64_t droppedTotal() const { return waiting_.droppedTotal(); }

 private:
  size_t count(size_t dropped) {
    dropped_since_taken_ += static_cast<uint32_t>(dropped);
    return dropped;
  }

  DropOldestQueue<Item> waiting_;
  uint32_t dropped_since_taken_ = 0;
};

}  // namespace gmm_localization
