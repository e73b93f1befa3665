#include "gmm_localization/core/localization/localizer_pipeline.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gmm_localization/core/common/option_checks.h"

namespace gmm_localization {

std::string LocalizerPipelineOptions::validate() const {
  const auto bad = rangeProblem;
  for (const std::string& e :
       {bad("odometry_buffer_s", odometry_buffer_s, 0.1, 3600.0),
        bad("odometry_max_extrapolation_s", odometry_max_extrapolation_s, 0.0, 10.0),
        bad("deskew_twist_max_gap_s", deskew_twist_max_gap_s, 0.0, 10.0),
        bad("scan_arrival_delay_s", scan_arrival_delay_s, 0.0, 10.0),
        bad("time_backwards_tolerance_s", time_backwards_tolerance_s, 0.0, 1e6)}) {
    if (!e.empty()) return e;
  }
  return {};
}

PosteriorEstimate posteriorFromState(const EkfState& state) {
  PosteriorEstimate p;
  p.stamp_s = state.time_s;
  p.map_T_base = state.pose();
  p.covariance = state.poseCovariance();
  p.twist.linear_mps = state.linearVelocity();
  p.twist.angular_radps = state.angularVelocity();
  return p;
}

std::optional<BodyTwist> deskewTwist(const ScanInput& scan, const OdometryBuffer& odometry,
                                     const PriorTracker& tracker, double max_gap_s) {
  float t_max = 0.f;
  for (float t : scan.time_s) {
    if (std::isfinite(t)) t_max = std::max(t_max, t);
  }
  const auto twist = odometry.twistAt(scan.stamp_s + 0.5 * t_max, max_gap_s);
  if (twist.ok()) return twist.value();
  if (tracker.hasPosterior() && std::abs(tracker.posterior().stamp_s - scan.stamp_s) <= max_gap_s) {
    return tracker.posterior().twist;
  }
  return std::nullopt;
}

Result<LocalizerPipeline> LocalizerPipeline::create(const LocalizerPipelineOptions& options) {
  using R = Result<LocalizerPipeline>;
  const std::string e = options.validate();
  if (!e.empty()) return R::failure("pipeline: " + e);
  auto filter = LocalizationFilter::create(options.ekf, options.filter);
  if (!filter) return R::failure(filter.error());
  auto processor = MatchProcessor::create(options.registration, options.policy);
  if (!processor) return R::failure(processor.error());
  return LocalizerPipeline(options, std::move(filter).value(), std::move(processor).value());
}

LocalizerPipeline::LocalizerPipeline(const LocalizerPipelineOptions& options,
                                     LocalizationFilter filter, MatchProcessor processor)
    : options_(options),
      filter_(std::move(filter)),
      processor_(std::move(processor)),
      tracker_(options.policy),
      odometry_(options.odometry_buffer_s, options.odometry_max_extrapolation_s,
                options.time_backwards_tolerance_s) {}

void LocalizerPipeline::setConfiguredPose(const Pose6& pose, bool z_known,
                                          const WindowExtent* window) {
  configured_pose_ = pose;
  configured_z_known_ = z_known;
  configured_window_.reset();
  if (window != nullptr) configured_window_ = *window;
  tracker_.setExplicitPose(pose, NAN, PriorSource::kConfigured, z_known, window);
}

Status LocalizerPipeline::setInitialPose(const Pose6& pose, const Matrix6d& covariance,
                                         double stamp_s, bool z_known) {
  advanceTo(stamp_s);
  // The matcher completes a planar pose from what it knows; the filter from its own state.
  bool completed_z = z_known;
  const Pose6 full = z_known ? pose : tracker_.completePlanarPose(pose, &odometry_, &completed_z);
  tracker_.setExplicitPose(full, stamp_s, PriorSource::kInitialPose, completed_z);
  return filter_.setInitialPose(pose, covariance, stamp_s, z_known);
}

Status LocalizerPipeline::relocalize(double stamp_s) {
  advanceTo(stamp_s);
  return filter_.relocalize(stamp_s);
}

void LocalizerPipeline::addImu(const ImuMeasurement& imu) {
  advanceTo(imu.stamp_s);
  filter_.addImu(imu);
}

void LocalizerPipeline::addOdometry(const OdometrySample& sample, const TwistMeasurement& twist) {
  advanceTo(sample.stamp_s);
  odometry_.add(sample);
  filter_.addTwist(twist);
}

void LocalizerPipeline::addScan(ScanInput scan, double processing_latency_s) {
  const double arrival = scan.stamp_s + options_.scan_arrival_delay_s;
  advanceTo(arrival);
  if (have_last_scan_ && scan.stamp_s < last_scan_stamp_s_ - options_.time_backwards_tolerance_s) {
    resetMatcher();
  }
  have_last_scan_ = true;
  last_scan_stamp_s_ = scan.stamp_s;
  if (!in_flight_) {
    start(std::move(scan), arrival, arrival, processing_latency_s);
    return;
  }
  if (waiting_) {
    ++dropped_since_report_;
    ++dropped_total_;
  }
  waiting_ = std::move(scan);
  waiting_arrival_s_ = arrival;
  waiting_latency_s_ = processing_latency_s;
}

void LocalizerPipeline::flush() {
  while (in_flight_) complete();
}

std::vector<PipelineScanReport> LocalizerPipeline::takeReports() {
  std::vector<PipelineScanReport> out;
  out.swap(reports_);
  return out;
}

void LocalizerPipeline::advanceTo(double t) {
  while (in_flight_ && in_flight_->finish_s <= t) complete();
}

void LocalizerPipeline::start(ScanInput scan, double arrival_s, double start_s, double latency_s) {
  // What the ekf nodelet last published before the worker picked the scan up.
  if (filter_.active()) {
    const auto state = filter_.stateAt(start_s);
    if (state.ok()) tracker_.setPosterior(posteriorFromState(state.value()));
  }
  const Prior prior = tracker_.priorAt(scan.stamp_s, &odometry_);
  std::optional<BodyTwist> twist;
  if (options_.deskew)
    twist = deskewTwist(scan, odometry_, tracker_, options_.deskew_twist_max_gap_s);
  PipelineScanReport r;
  r.arrival_s = arrival_s;
  r.start_s = start_s;
  r.dropped_before = dropped_since_report_;
  dropped_since_report_ = 0;
  static const ChunkMap kEmpty;
  r.match =
      processor_.process(map_ ? *map_ : kEmpty, std::move(scan), prior, twist ? &*twist : nullptr,
                         options_.record_traversal, options_.clock);
  const double latency = latency_s >= 0.0 ? latency_s : r.match.total_s;
  r.finish_s = start_s + std::max(0.0, latency);
  in_flight_ = std::move(r);
}

void LocalizerPipeline::complete() {
  PipelineScanReport r = std::move(*in_flight_);
  in_flight_.reset();
  // Matcher side: the outcome feeds the relocalization state machine.
  const MatchReport& m = r.match;
  if (m.outcome == MatchOutcome::kAccepted) {
    tracker_.onAccepted(m.stamp_s, m.pose, planarCovariance(m.covariance), m.prior);
    // EKF side: the published pose arrives (a delayed measurement).
    r.offered_to_filter = true;
    r.fuse = filter_.addMatch(m.stamp_s, m.pose, m.covariance);
  } else if (m.outcome == MatchOutcome::kRejected) {
    tracker_.onRejected();
  }
  const double finish = r.finish_s;
  reports_.push_back(std::move(r));
  if (waiting_) {
    ScanInput next = std::move(*waiting_);
    waiting_.reset();
    start(std::move(next), waiting_arrival_s_, std::max(finish, waiting_arrival_s_),
          waiting_latency_s_);
  }
}

void LocalizerPipeline::resetMatcher() {
  // A match running on the old timeline is discarded (the nodelet's worker does the same).
  if (in_flight_) {
    PipelineScanReport r = std::move(*in_flight_);
    r.match.outcome = MatchOutcome::kSkipped;
    r.match.reason = "discarded: time went backwards during the match";
    reports_.push_back(std::move(r));
    in_flight_.reset();
  }
  waiting_.reset();
  tracker_.reset();
  ++resets_;
  if (configured_pose_ && options_.configured_pose_on_reset) {
    tracker_.setExplicitPose(*configured_pose_, NAN, PriorSource::kConfigured, configured_z_known_,
                             configured_window_ ? &*configured_window_ : nullptr);
  }
}

}  // namespace gmm_localization
