#include "gmm_localization/core/localization/match_processor.h"

#include <cmath>
#include <string>

#include "gmm_localization/core/matching/reflectivity_scan.h"
#include "gmm_localization/core/raster/window_coverage.h"

namespace gmm_localization {
namespace {

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

const char* matchOutcomeName(MatchOutcome outcome) {
  switch (outcome) {
    case MatchOutcome::kAccepted:
      return "accepted";
    case MatchOutcome::kRejected:
      return "rejected";
    default:
      return "skipped";
  }
}

const char* matchMethodName(MatchMethod method) {
  switch (method) {
    case MatchMethod::kReflectivity:
      return "reflectivity";
    case MatchMethod::kFused:
      return "fused";
    default:
      return "height";
  }
}

bool parseMatchMethod(const std::string& name, MatchMethod* out) {
  for (MatchMethod m : {MatchMethod::kHeight, MatchMethod::kReflectivity, MatchMethod::kFused}) {
    if (name == matchMethodName(m)) {
      *out = m;
      return true;
    }
  }
  return false;
}

std::string MatchMethodOptions::validate() const {
  const ReflectivityLayerOptions& r = reflectivity;
  if (!(r.metres_per_unit > 0.0 && r.metres_per_unit <= 1.0))
    return "reflectivity/metres_per_unit must be in (0, 1]";
  if (!(std::isfinite(r.ground_height_m) && std::abs(r.ground_height_m) <= 10.0))
    return "reflectivity/ground_height_m must be within +-10 m";
  if (!(r.ground_min_m < r.ground_max_m && r.ground_min_m >= -2.0 && r.ground_max_m <= 2.0))
    return "reflectivity/ground_min_m < ground_max_m, both within +-2 m";
  if (!(r.max_range_m > 0.0 && r.max_range_m <= 200.0))
    return "reflectivity/max_range_m must be in (0, 200]";
  return {};
}

Result<MatchProcessor> MatchProcessor::create(const RegistrationOptions& registration,
                                              const LocalizationPolicyOptions& policy,
                                              const MatchMethodOptions& method,
                                              bool defer_obstacles) {
  std::string e = registration.validate();
  if (!e.empty()) return Result<MatchProcessor>::failure("registration: " + e);
  e = policy.validate();
  if (!e.empty()) return Result<MatchProcessor>::failure("policy: " + e);
  e = method.validate();
  if (!e.empty()) return Result<MatchProcessor>::failure("method: " + e);
  // Deferred labels: the registrations leave them out, labelObstacles() adds them.
  const bool deferred = defer_obstacles && registration.classify_obstacles &&
                        method.method != MatchMethod::kReflectivity;
  RegistrationOptions tracking = registration;
  if (deferred) tracking.classify_obstacles = false;
  RegistrationOptions unknown_z = tracking;
  unknown_z.z_search_m = std::max(registration.z_search_m, policy.window.unknown_z_search_m);
  return MatchProcessor(registration, tracking, unknown_z,
                        reflectivityRegistrationOptions(registration), policy, method, deferred);
}

void MatchProcessor::labelObstacles(const ChunkMap& map, MatchReport& report,
                                    const std::function<double()>& now) const {
  if (!deferred_labels_ || !report.has_result ||
      report.result.obstacles.label.size() == report.points.size()) {
    return;
  }
  const double t0 = now ? now() : 0.0;
  report.result.obstacles = classifyObstacles(map, report.points, report.result.pose,
                                              options_.obstacles, tracking_.pool().get());
  if (now) {
    const double dt = now() - t0;
    report.timing.obstacles_s += dt;
    report.total_s += dt;
  }
}

MatchReport MatchProcessor::process(const ChunkMap& map, ScanInput scan, const Prior& prior,
                                    const BodyTwist* twist, bool want_traversal,
                                    const std::function<double()>& now,
                                    const ChunkMap* reflectivity_map,
                                    const std::atomic<bool>* cancel) const {
  const double t0 = now ? now() : 0.0;
  MatchReport r;
  r.stamp_s = scan.stamp_s;
  r.prior = prior;
  r.input_points = scan.points.size();
  size_t finite = 0;
  for (const Eigen::Vector3f& p : scan.points) finite += p.allFinite() ? 1 : 0;
  r.dropped_nonfinite = r.input_points - finite;
  r.time_source = scan.time_source;
  // Why the scan is not deskewed, unless it is (cleared then).
  if (scan.time_s.empty()) {
    r.deskew_note = !scan.time_problem.empty()
                        ? scan.time_problem
                        : "the cloud has no per-point time field ('time', 't' or 'timestamp')";
  } else if (twist == nullptr) {
    r.deskew_note =
        "no twist: deskew off, or no INS twist within deskew_twist_max_gap_s of mid-scan";
  } else {
    r.deskew_note = "scan skipped before deskewing";
  }
  auto finish = [&](MatchOutcome outcome, std::string reason) {
    r.outcome = outcome;
    r.reason = std::move(reason);
    r.points = std::move(scan.points);
    if (now) r.total_s = now() - t0;
    return r;
  };

  if (!std::isfinite(scan.stamp_s)) return finish(MatchOutcome::kSkipped, "scan stamp not finite");
  if (!prior.valid()) {
    return finish(MatchOutcome::kSkipped,
                  "no prior: waiting for an initial pose (/initialpose or the configured pose) "
                  "or the EKF posterior");
  }
  if (map.size() == 0) return finish(MatchOutcome::kSkipped, "no map: no chunks received yet");
  if (finite == 0) {
    return finish(MatchOutcome::kSkipped, "scan has no finite points (" +
                                              std::to_string(r.input_points) + " in the cloud)");
  }

  // Motion compensation: every point moved into base_link at the stamp.
  if (twist != nullptr && !scan.time_s.empty()) {
    if (deskew(scan.points, scan.time_s, twist->linear_mps, twist->angular_radps)) {
      r.deskewed = true;
      r.deskew_note.clear();
    } else {
      r.deskew_note = "per-point times and points differ in number";
    }
  }

  r.window = searchWindowFor(prior, policy_.window);
  MatchRequest request;
  request.prior = prior.pose;
  request.half_x_m = r.window.half_x_m;
  request.half_y_m = r.window.half_y_m;
  request.half_heading_rad = r.window.half_heading_rad;
  request.has_reference = scan.has_reference;
  request.reference = scan.reference;
  request.cancel = cancel;
  // The reflectivity layer: levelled ground returns with their intensity as z (x, y, heading);
  // the fused method: those returns as the second channel of the height match.
  const bool reflectivity = method_.method == MatchMethod::kReflectivity;
  const bool fused = method_.method == MatchMethod::kFused;
  PointList reflectivity_points;
  FusedChannel fused_channel;
  if (method_.needsIntensity()) {
    if (scan.intensity.size() != scan.points.size()) {
      return finish(MatchOutcome::kSkipped, std::string("the cloud has no intensity field: the ") +
                                                matchMethodName(method_.method) +
                                                " method needs one");
    }
    if (fused && reflectivity_map == nullptr) {
      return finish(MatchOutcome::kSkipped,
                    "no reflectivity map: the fused method needs the map's reflectivity layer");
    }
    reflectivity_points = reflectivityPoints(scan.points, scan.intensity, prior.pose.roll,
                                             prior.pose.pitch, method_.reflectivity);
  }
  if (reflectivity) {
    for (Pose6* p : {&request.prior, &request.reference}) p->z = p->roll = p->pitch = 0.0;
  }
  if (fused) {
    fused_channel.map = reflectivity_map;
    fused_channel.points = std::move(reflectivity_points);
    request.fused = &fused_channel;
  }
  const Registration& registration =
      reflectivity ? reflectivity_ : (prior.z_known ? tracking_ : unknown_z_);
  std::vector<TraversalNode>* traversal = want_traversal ? &r.traversal : nullptr;
  r.global_window = registration.searchesGlobally(discreteWindow(
      request, registration.options().heading_step_rad, map.geometry().resolution_m));
  auto match = registration.match(map, reflectivity ? reflectivity_points : scan.points, request,
                                  traversal, now, &r.timing);
  // A global window larger than the map the server holds is searched over the loaded part
  // only: a rejection says how much of it that was.
  auto globalCoverage = [&]() -> std::string {
    if (!prior.lost) return {};
    const WindowCoverage c =
        windowCoverage(map, prior.pose.x, prior.pose.y, r.window.half_x_m, r.window.half_y_m);
    if (c.loaded_share >= 0.999) return {};
    return " (global search: " +
           describeWindowCoverage(c, prior.pose.x, prior.pose.y, r.window.half_x_m) + ")";
  };
  if (!match.ok()) {
    // Off the map, too little coverage, empty after filtering: a failed attempt (counts
    // towards relocalization only when points were left to search with).
    const bool no_points = match.errorKind() == RegistrationError::kNoPoints;
    return finish(no_points ? MatchOutcome::kSkipped : MatchOutcome::kRejected,
                  match.error() + globalCoverage());
  }
  r.has_result = true;
  r.result = std::move(match).value();
  if (reflectivity) {  // the layer says nothing of height and tilt: the prior's stand
    r.result.pose.z = prior.pose.z;
    r.result.pose.roll = prior.pose.roll;
    r.result.pose.pitch = prior.pose.pitch;
  }
  const MatchResult& m = r.result;
  r.search_points = m.filtered.points.size();
  r.dropped_nonfinite = m.filtered.dropped_nonfinite;
  // The window actually searched is centred on the height-aligned prior.
  MatchRequest aligned = request;
  aligned.prior.z += m.z_offset_m;
  r.search_window =
      discreteWindow(aligned, registration.options().heading_step_rad, map.geometry().resolution_m);
  r.correction_xy_m = std::hypot(m.pose.x - prior.pose.x, m.pose.y - prior.pose.y);
  r.correction_yaw_rad = wrap(m.pose.yaw - prior.pose.yaw);

  const AcceptanceDecision d =
      acceptMatch(m, r.search_window, policy_.acceptance, prior.wide || prior.lost,
                  prior.recent_log_likelihood_per_point, prior.interim);
  if (!d.accepted) {
    r.likelihood_collapsed = d.likelihood_collapsed;
    return finish(MatchOutcome::kRejected, d.reason + globalCoverage());
  }
  r.pose = m.pose;
  // A certificate switched off proves nothing either way: the covariance stays as it was.
  const bool certified =
      m.certificate.certified || m.certificate.failure == CertificateFailure::kDisabled;
  r.covariance = publishedPoseCovariance(m.covariance_xyh, policy_.covariance, certified);
  if (!r.covariance.allFinite()) {
    return finish(MatchOutcome::kRejected, "numerical failure: non-finite covariance");
  }
  return finish(MatchOutcome::kAccepted, {});
}

}  // namespace gmm_localization
