#include "gmm_localization/core/localization/localizer_pipeline.h"

#include <algorithm>
#include <limits>

#include "gmm_localization/core/common/option_checks.h"

namespace gmm_localization {

std::string LocalizerPipelineOptions::validate() const {
  const std::string e = session.validate();
  if (!e.empty()) return e;
  std::string r = rangeProblem("scan_arrival_delay_s", scan_arrival_delay_s, 0.0, 10.0);
  if (r.empty()) {
    r = rangeProblem("global_search_latency_s", global_search_latency_s, -1.0, 600.0);
  }
  return r;
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

Result<LocalizerPipeline> LocalizerPipeline::create(const LocalizerPipelineOptions& options) {
  using R = Result<LocalizerPipeline>;
  const std::string e = options.validate();
  if (!e.empty()) return R::failure("pipeline: " + e);
  auto filter = LocalizationFilter::create(options.ekf, options.filter);
  if (!filter) return R::failure(filter.error());
  auto processor = MatchProcessor::create(options.registration, options.policy, options.method);
  if (!processor) return R::failure(processor.error());
  return LocalizerPipeline(options, std::move(filter).value(), std::move(processor).value());
}

LocalizerPipeline::LocalizerPipeline(const LocalizerPipelineOptions& options,
                                     LocalizationFilter filter, MatchProcessor processor)
    : options_(options),
      filter_(std::move(filter)),
      processor_(std::move(processor)),
      session_(options.session, options.policy) {}

void LocalizerPipeline::setConfiguredPose(const Pose6& pose, bool z_known,
                                          const WindowExtent* window) {
  session_.setConfiguredPose(pose, z_known, window);
}

Status LocalizerPipeline::setInitialPose(const Pose6& pose, const Matrix6d& covariance,
                                         double stamp_s, bool z_known) {
  advanceTo(stamp_s);
  // The matcher completes a planar pose from what it knows; the filter from its own state.
  session_.setInitialPose(pose, stamp_s, z_known);
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
  session_.addOdometry(sample);
  filter_.addTwist(twist);
}

FuseReport LocalizerPipeline::addGnss(const GnssFix& fix) {
  advanceTo(fix.stamp_s);
  return filter_.addGnss(fix);
}

void LocalizerPipeline::addScan(ScanInput scan, double processing_latency_s) {
  const double arrival = scan.stamp_s + options_.scan_arrival_delay_s;
  advanceTo(arrival);
  // Time going backwards resets the session and drops the waiting scans; a match running on
  // the old timeline is completed now and discarded by the epoch check (the nodelet's worker
  // discards it when it finishes).
  const auto a = session_.onScanArrival(scan.stamp_s, arrival);
  if (!a.refused.empty()) {  // answered at once, as the nodelet does
    PipelineScanReport r;
    r.arrival_s = r.start_s = r.finish_s = arrival;
    r.match.stamp_s = scan.stamp_s;
    r.match.input_points = scan.points.size();
    r.match.outcome = MatchOutcome::kSkipped;
    r.match.reason = a.refused;
    reports_.push_back(std::move(r));
    return;
  }
  if (a.timeWentBackwards()) {
    while (anyInFlight()) completeFirst();
  }
  session_.enqueue(WaitingScan{std::move(scan), arrival, processing_latency_s});
  if (!in_flight_) startNext(arrival);
}

void LocalizerPipeline::flush() {
  while (anyInFlight()) completeFirst();
}

std::vector<PipelineScanReport> LocalizerPipeline::takeReports() {
  std::vector<PipelineScanReport> out;
  out.swap(reports_);
  return out;
}

void LocalizerPipeline::advanceTo(double t) {
  auto first = [this]() {
    double f = std::numeric_limits<double>::infinity();
    if (in_flight_) f = in_flight_->report.finish_s;
    if (global_in_flight_) f = std::min(f, global_in_flight_->report.finish_s);
    return f;
  };
  while (anyInFlight() && first() <= t) completeFirst();
}

void LocalizerPipeline::startNext(double now) {
  auto next = session_.takeNext();
  WaitingScan& w = next.item;
  const double start_s = std::max(now, w.arrival_s);
  // What the ekf nodelet last published before the worker picked the scan up.
  if (filter_.active()) {
    const auto state = filter_.stateAt(start_s);
    if (state.ok()) session_.setPosterior(posteriorFromState(state.value()));
  }
  const MatchStart m = session_.beginMatch(w.scan, /*global_available=*/!global_in_flight_);
  PipelineScanReport r;
  r.arrival_s = w.arrival_s;
  r.start_s = start_s;
  r.dropped_before = next.dropped_before;
  if (!m.skip_reason.empty()) {  // answered at once, as the nodelet's worker does
    r.finish_s = start_s;
    r.match.stamp_s = w.scan.stamp_s;
    r.match.input_points = w.scan.points.size();
    r.match.outcome = MatchOutcome::kSkipped;
    r.match.reason = m.skip_reason;
    r.match.prior = m.prior;
    r.match.mode_after = session_.tracker().mode();
    filter_.onMatcherMode(r.match.stamp_s, r.match.mode_after);  // the status the EKF reads
    reports_.push_back(std::move(r));
    if (session_.hasWaiting()) startNext(start_s);
    return;
  }
  static const ChunkMap kEmpty;
  r.match = processor_.process(map_ ? *map_ : kEmpty, std::move(w.scan), m.prior, m.twistOrNull(),
                               options_.record_traversal, options_.clock, reflectivity_map_.get());
  double latency = w.latency_s >= 0.0 ? w.latency_s : r.match.total_s;
  if (m.global() && options_.global_search_latency_measured) {
    latency = r.match.total_s;
  } else if (m.global() && options_.global_search_latency_s >= 0.0) {
    latency = options_.global_search_latency_s;
  }
  r.finish_s = start_s + std::max(0.0, latency);
  if (m.global()) {
    // The global worker takes it; the worker is free for the next scan at once.
    global_in_flight_ = InFlight{std::move(r), m.epoch};
    if (session_.hasWaiting()) startNext(start_s);
    return;
  }
  in_flight_ = InFlight{std::move(r), m.epoch};
}

void LocalizerPipeline::completeFirst() {
  const bool global_first =
      global_in_flight_ &&
      (!in_flight_ || global_in_flight_->report.finish_s < in_flight_->report.finish_s);
  std::optional<InFlight>& slot = global_first ? global_in_flight_ : in_flight_;
  InFlight f = std::move(*slot);
  slot.reset();
  PipelineScanReport& r = f.report;
  // Matcher side: the outcome feeds the relocalization state machine (or is discarded).
  if (session_.finishMatch(f.epoch, &r.match) && r.match.accepted()) {
    // EKF side: the published pose arrives (a delayed measurement).
    const MatchReport& m = r.match;
    r.offered_to_filter = true;
    r.fuse = filter_.addMatch(m.stamp_s, m.pose, m.covariance);
  }
  // EKF side: the status of the scan (the matcher's mode after it).
  filter_.onMatcherMode(r.match.stamp_s, r.match.mode_after);
  const double finish = r.finish_s;
  reports_.push_back(std::move(r));
  if (!in_flight_ && session_.hasWaiting()) startNext(finish);
}

}  // namespace gmm_localization
