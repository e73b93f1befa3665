#include "evaluate/evaluate_localize.h"
#include "evaluate/evaluate_integrity.h"

#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <ostream>

#include "common/progress_bar.h"
#include "evaluate/evaluate_gnss.h"
#include "evaluate/evaluate_map.h"
#include "evaluate/evaluate_yaml.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/localization/localizer_pipeline.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/ros/matcher_options.h"

namespace gmm_localization {
namespace eval {
namespace {

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Feeds the bag's messages to the pipeline and turns what comes out into rows.
class BagRun {
 public:
  BagRun(const BagEvaluationConfig& c, const node::MatcherOptions& matcher,
         LocalizerPipeline& pipeline, const Trajectory& truth, size_t total_scans,
         OffsetExperiment* offsets, EvaluationResults& out)
      : c_(c),
        matcher_(matcher),
        pipeline_(pipeline),
        truth_(truth),
        offsets_(offsets),
        out_(out),
        offset_stride_(c.offset_scans > 0
                           ? std::max<size_t>(1, total_scans / static_cast<size_t>(c.offset_scans))
                           : 0),
        total_scans_(total_scans),
        progress_("evaluate", c.progress) {}

  void imu(const ImuMeasurement& m) {
    sampleEkf(m.stamp_s);
    pipeline_.addImu(m);
    collect();
  }
  void odometry(const OdometrySample& s, const TwistMeasurement& t) {
    sampleEkf(s.stamp_s);
    pipeline_.addOdometry(s, t);
    collect();
  }
  void scan(LabelledScan&& s) {
    const double stamp = s.scan.stamp_s;
    if (!started_) start(stamp);
    last_scan_s_ = stamp;
    sampleEkf(stamp + pipeline_.options().scan_arrival_delay_s);
    const auto truth = truth_.at(stamp, kTruthGapS);
    if (offsets_ != nullptr && truth && scan_index_ % offset_stride_ == 0 &&
        offsets_submitted_ < static_cast<size_t>(c_.offset_scans)) {
      const std::optional<BodyTwist> twist = pipeline_.session().deskewTwistFor(s.scan);
      offsets_->submit(s.scan, toPose6(*truth), twist);
      ++offsets_submitted_;
    }
    ++scan_index_;
    if (!s.label.empty()) labels_[stamp] = std::move(s.label);
    if (truth) {  // the certificate's calibration: the truth's search score
      s.scan.has_reference = true;
      s.scan.reference = toPose6(*truth);
    }
    pipeline_.addScan(std::move(s.scan), c_.latency_s);
    collect();
    showProgress(false);
  }
  bool done() const { return started_ && last_scan_s_ - first_scan_s_ >= c_.max_duration_s; }

  void finish() {
    pipeline_.flush();
    collect();
    sampleEkf(last_scan_s_ + 0.1);
    out_.info.duration_s = started_ ? last_scan_s_ - first_scan_s_ + 0.1 : 0.0;
    out_.info.scans_in_bag = scan_index_;
    out_.info.dropped_scans = pipeline_.droppedScans();
    showProgress(true);
  }

 private:
  /// Scans done of the bag's (or of max_duration_s), matches so far, Fig. 8 scans submitted.
  void showProgress(bool final_line) {
    const double by_count =
        total_scans_ > 0 ? double(scan_index_) / double(total_scans_) : std::nan("");
    const double by_time = std::isfinite(c_.max_duration_s) && c_.max_duration_s > 0.0
                               ? (last_scan_s_ - first_scan_s_) / c_.max_duration_s
                               : std::nan("");
    const double fraction = std::isfinite(by_time) ? std::max(by_count, by_time) : by_count;
    const std::string detail =
        "scan " + tools::withCommas(scan_index_) + "/" + tools::withCommas(total_scans_) + ", " +
        tools::withCommas(out_.matches.size()) + " matches" +
        (offsets_ != nullptr ? ", Fig. 8 scans " + std::to_string(offsets_submitted_)
                             : std::string());
    if (final_line) {
      progress_.finish(detail);
    } else {
      progress_.update(std::min(fraction, 0.999), detail);  // 100 % is finish()'s line
    }
  }

  void start(double stamp) {
    started_ = true;
    first_scan_s_ = stamp;
    next_ekf_s_ = stamp;
    if (matcher_.initial_pose_enabled) {
      const WindowExtent w = node::configuredPoseWindow(matcher_);
      pipeline_.setConfiguredPose(matcher_.initial_pose, matcher_.initial_pose_z_known, &w);
      out_.info.notes.push_back("initial pose from matcher.yaml initial_pose/*");
      return;
    }
    const auto truth = truth_.at(stamp, kTruthGapS);
    if (!truth) {
      out_.info.notes.push_back("no ground truth at the first scan: no initial pose");
      return;
    }
    Pose6 p = toPose6(*truth);
    p.x += c_.initial_dx_m;
    p.y += c_.initial_dy_m;
    p.yaw = wrapAngle(p.yaw + c_.initial_dyaw_rad);
    const WindowExtent w = node::configuredPoseWindow(matcher_);
    pipeline_.setConfiguredPose(p, true, &w);
  }

  void sampleEkf(double now) {
    if (!started_) return;
    const double dt = 1.0 / c_.ekf_rate_hz;
    for (; next_ekf_s_ <= now; next_ekf_s_ += dt) {
      const auto truth = truth_.at(next_ekf_s_, kTruthGapS);
      if (!truth) continue;
      const auto state = pipeline_.stateAt(next_ekf_s_);
      if (!state) {
        ++out_.info.ekf_inactive_samples;
        continue;
      }
      EkfRow row;
      row.t = next_ekf_s_;
      row.estimate = planar(fromIsometry(state->pose()), next_ekf_s_);
      row.truth = *truth;
      row.error = vehicleFrameError(row.estimate, row.truth);
      const Matrix6d cov = state->poseCovariance();
      row.sigma_x_m = std::sqrt(std::max(0.0, cov(0, 0)));
      row.sigma_y_m = std::sqrt(std::max(0.0, cov(1, 1)));
      row.sigma_yaw_rad = std::sqrt(std::max(0.0, cov(5, 5)));
      row.twist_scale = state->twistScale();
      row.gnss_bias_x_m = state->gnssBias().x();
      row.gnss_bias_y_m = state->gnssBias().y();
      out_.ekf.push_back(row);
    }
  }

  void collect() {
    for (PipelineScanReport& r : pipeline_.takeReports()) out_.matches.push_back(rowOf(r));
  }

  MatchRow rowOf(const PipelineScanReport& p) {
    const MatchReport& m = p.match;
    MatchRow row;
    row.stamp_s = m.stamp_s;
    row.outcome = matchOutcomeName(m.outcome);
    row.reason = m.reason;
    row.prior_source = priorSourceName(m.prior.source);
    row.wide = m.prior.wide;
    row.window_half_x_m = m.window.half_x_m;
    row.window_half_heading_rad = m.window.half_heading_rad;
    row.input_points = m.input_points;
    row.search_points = m.search_points;
    row.filter_ms = m.timing.filter_s * 1000.0;
    row.search_ms = m.timing.search_s * 1000.0;
    row.refine_ms = m.timing.refine_s * 1000.0;
    row.total_ms = m.total_s * 1000.0;
    row.latency_s = p.finish_s - m.stamp_s;
    row.dropped_before = p.dropped_before;
    if (p.offered_to_filter) row.fuse = outcomeName(p.fuse.outcome);
    if (m.has_result) {
      row.evaluations = static_cast<uint64_t>(m.result.search.stats.evaluations);
      row.search_fraction = m.result.search.stats.fraction();
      row.log_likelihood_per_point = m.result.log_likelihood_per_point;
      row.map_coverage = m.result.map_coverage;
      row.integrity = integrityOf(m.result);
      row.integrity.certificate_ms = m.timing.certificate_s * 1000.0;
      const auto truth = truth_.at(m.stamp_s, kTruthGapS);
      if (truth) {
        row.has_pose = true;
        row.pose = planar(m.result.pose, m.stamp_s);
        row.error = vehicleFrameError(row.pose, *truth);
        row.truth = *truth;
      }
    }
    auto labels = labels_.find(m.stamp_s);
    if (labels != labels_.end()) {
      if (m.accepted()) countObstacles(m, labels->second, row);
      labels_.erase(labels);
    }
    return row;
  }

  void countObstacles(const MatchReport& m, const std::vector<uint8_t>& labels, MatchRow& row) {
    const std::vector<PointClass>& predicted = m.result.obstacles.label;
    if (predicted.size() != labels.size() || m.points.size() != labels.size()) return;
    ObstacleStats& s = out_.obstacles;
    ++s.scans;
    out_.has_obstacles = true;
    for (size_t i = 0; i < labels.size(); ++i) {
      const Eigen::Vector3f& q = m.points[i];
      if (!q.allFinite()) continue;
      const bool actual = labels[i] != 0;
      const bool obstacle = predicted[i] == PointClass::kObstacle;
      row.obstacles.add(obstacle, actual);
      const double range = std::hypot(q.x(), q.y());
      const size_t bin = std::min<size_t>(3, static_cast<size_t>(range / 20.0));
      s.by_range[bin].add(obstacle, actual);
      if (labels[i] < 3) {
        ++s.positives_by_label[labels[i]];
        s.detected_by_label[labels[i]] += obstacle ? 1 : 0;
      }
    }
    s.all += row.obstacles;
  }

  const BagEvaluationConfig& c_;
  const node::MatcherOptions& matcher_;
  LocalizerPipeline& pipeline_;
  const Trajectory& truth_;
  OffsetExperiment* offsets_;
  EvaluationResults& out_;
  size_t offset_stride_;
  size_t total_scans_;
  tools::ProgressBar progress_;
  size_t offsets_submitted_ = 0;
  size_t scan_index_ = 0;
  bool started_ = false;
  double first_scan_s_ = 0.0, last_scan_s_ = 0.0, next_ekf_s_ = 0.0;
  std::map<double, std::vector<uint8_t>> labels_;
};

}  // namespace

Result<EvaluationResults> runBagEvaluation(const BagEvaluationConfig& c, std::ostream& log,
                                           TraversalFigure* traversal) {
  using R = Result<EvaluationResults>;
  node::MatcherOptions matcher;
  node::EkfNodeOptions ekf;
  RasterOptions raster;
  try {
    // Unknown keys of the files (typos) are named on stderr.
    matcher = loadYamlOptions(node::loadMatcherOptions, c.matcher_yaml, c.matcher_overrides);
    ekf = loadYamlOptions(node::loadEkfNodeOptions, c.ekf_yaml, c.ekf_overrides);
    raster = loadMapServerYamlRaster(c.map_server_yaml);
  } catch (const node::ConfigError& e) {
    return R::failure(e.what());
  }
  LocalizerPipelineOptions po = node::pipelineOptions(matcher, ekf);
  po.scan_arrival_delay_s =
      c.arrival_delay_s >= 0.0 ? c.arrival_delay_s : medianScanRecordDelay(c.bag, c.topics.cloud);
  po.clock = steadySeconds;
  po.global_search_latency_s = c.global_latency_s;
  po.global_search_latency_measured = c.global_latency_s < 0.0;
  auto pipeline = LocalizerPipeline::create(po);
  if (!pipeline) return R::failure(pipeline.error());

  log << "reading the ground truth of " << c.bag << " ..." << std::endl;
  auto truth = readTrajectory(c.bag, c.topics.ground_truth);
  if (!truth) return R::failure(truth.error());
  const size_t total_scans = countMessages(c.bag, c.topics.cloud);
  log << "  " << truth->size() << " poses over " << truth->endTime() - truth->startTime() << " s, "
      << total_scans << " scans" << std::endl;

  log << "rasterizing the map along the route (" << c.raster_radius_m << " m) ..." << std::endl;
  RouteMapStats map_stats;
  const MatchMethod method = po.method.method;
  auto map = rasterizeAlongRoute(
      c.map, raster, *truth, c.raster_radius_m, c.threads, &map_stats,
      method == MatchMethod::kReflectivity ? MapLayer::kReflectivity : MapLayer::kHeight);
  if (!map) return R::failure(map.error());
  log << "  " << map_stats.tiles << " tiles, " << map_stats.chunks << " chunks, "
      << map_stats.bytes / 1e6 << " MB in " << map_stats.seconds << " s" << std::endl;
  pipeline->setMap(*map);
  // The fused method's second map: the reflectivity layer beside the height map.
  std::shared_ptr<const ChunkMap> reflectivity_map;
  if (method == MatchMethod::kFused) {
    if (c.reflectivity_map.empty()) {
      return R::failure(
          "the matcher's method is fused: run evaluate with --method fused (it "
          "loads MAP and MAP/reflectivity)");
    }
    RouteMapStats stats;
    auto second = rasterizeAlongRoute(c.reflectivity_map, raster, *truth, c.raster_radius_m,
                                      c.threads, &stats, MapLayer::kReflectivity);
    if (!second) return R::failure("--method fused: " + second.error());
    const std::string incompatible = channelCompatibility(**map, **second);
    if (!incompatible.empty()) {
      return R::failure("--method fused: '" + c.map + "' and '" + c.reflectivity_map +
                        "' cannot be searched together: " + incompatible);
    }
    log << "  reflectivity layer: " << stats.tiles << " tiles, " << stats.chunks << " chunks, "
        << stats.bytes / 1e6 << " MB in " << stats.seconds << " s" << std::endl;
    map_stats.seconds += stats.seconds;
    reflectivity_map = *second;
    pipeline->setReflectivityMap(reflectivity_map);
  }

  EvaluationResults out;
  out.info.mode = "bag";
  out.info.dataset = c.dataset;
  out.info.bag = c.bag;
  out.info.map = c.map;
  out.info.map_wall_s = map_stats.seconds;
  out.info.virtual_latency_s = c.latency_s;
  out.info.scan_arrival_delay_s = po.scan_arrival_delay_s;

  auto processor = MatchProcessor::create(po.registration, po.policy, po.method);
  if (!processor) return R::failure(processor.error());
  std::unique_ptr<OffsetExperiment> offsets;
  if (c.offset_scans > 0) {
    offsets = std::make_unique<OffsetExperiment>(*processor, *map, c.offsets, steadySeconds,
                                                 reflectivity_map);
  }
  BagRun run(c, matcher, *pipeline, *truth, total_scans, offsets.get(), out);
  BagVisitor v;
  if (ekf.use_imu) v.imu = [&](const ImuMeasurement& m) { run.imu(m); };
  v.odometry = [&](const OdometrySample& s, const TwistMeasurement& t) { run.odometry(s, t); };
  v.scan = [&](LabelledScan&& s) { run.scan(std::move(s)); };
  v.done = [&]() { return run.done(); };
  const Status gnss = attachGnss(ekf, c.map, &*pipeline, &v, &out, log);  // evaluate --gps
  if (!gnss) return R::failure(gnss.error());
  if (!ekf.use_odom_twist) {
    out.info.notes.push_back(
        "use_odom_twist false is not modelled offline: the INS twist is fused");
  }
  log << "localizing (" << (c.latency_s >= 0 ? "fixed" : "measured") << " match latency";
  if (c.latency_s >= 0) log << " " << c.latency_s << " s";
  log << ", scans arrive " << po.scan_arrival_delay_s << " s after their stamp, global searches "
      << (c.global_latency_s >= 0 ? std::to_string(c.global_latency_s) + " s" : "measured")
      << ") ..." << std::endl;
  const double t0 = steadySeconds();
  auto stats = visitLocalizationBag(c.bag, c.topics, v);
  if (!stats) return R::failure(stats.error());
  run.finish();
  if (offsets) {
    out.offsets = offsets->finish();
    if (traversal != nullptr) *traversal = offsets->traversal();
  }
  out.info.wall_s = steadySeconds() - t0;
  for (const std::string& p : stats->problems) out.info.notes.push_back("bag: " + p);
  if (out.info.virtual_latency_s >= 0.0) {
    out.info.notes.push_back(
        "deterministic run: every match takes the fixed virtual latency; the measured "
        "processing times are reported beside it");
  }
  return out;
}

}  // namespace eval
}  // namespace gmm_localization
