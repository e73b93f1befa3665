#include "gmm_localization/core/matching/registration.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>

#include "gmm_localization/core/matching/reflectivity_scan.h"

namespace gmm_localization {

Registration::Registration(const RegistrationOptions& options, std::shared_ptr<TaskPool> pool,
                           std::shared_ptr<TaskPool> global_pool)
    : options_(options), pool_(std::move(pool)), global_pool_(std::move(global_pool)) {
  if (pool_ == nullptr && TaskPool::resolve(options_.threads) > 1) {
    pool_ = std::make_shared<TaskPool>(options_.threads);
  }
  if (global_pool_ == nullptr) {
    const int n = TaskPool::resolve(options_.global.threads);
    if (n == TaskPool::resolve(options_.threads)) {
      global_pool_ = pool_;
    } else if (n > 1) {
      global_pool_ = std::make_shared<TaskPool>(options_.global.threads);
    }
  }
}

namespace {

bool finitePose(const Pose6& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
         std::isfinite(p.pitch) && std::isfinite(p.yaw);
}

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

/// The protection level of `published`, refined from grid pose `grid` whose certificate is `c`
/// (MatchResult::protection_xy_m): the certificate's plus a cell's diagonal and the shift from
/// the grid pose in x-y [m]; plus a heading step and the shift in heading [rad].
struct Protection {
  double xy_m;
  double heading_rad;
};
Protection protectionOf(const MatchCertificate& c, const Pose6& grid, const Pose6& published,
                        double resolution_m, double heading_step_rad) {
  return {
      c.protection_xy_m + resolution_m * std::sqrt(2.0) +
          std::hypot(published.x - grid.x, published.y - grid.y),
      c.protection_heading_rad + heading_step_rad + std::abs(wrapAngle(published.yaw - grid.yaw))};
}

/// Optimum's score minus the best score of the grid poses around `reference` (the two nearest
/// translations per axis and the two nearest headings: the truth lies between them), per scan
/// point; NaN when none of them is inside the window.
double referenceDeficitPerPoint(const SearchProblem& problem, const SearchOutcome& optimum,
                                const Pose6& reference) {
  const SearchWindow& w = problem.window();
  const double res = problem.map().geometry().resolution_m;
  const double fx = (reference.x - w.prior.x) / res + w.half_x;
  const double fy = (reference.y - w.prior.y) / res + w.half_y;
  const double fj = wrapAngle(reference.yaw - w.prior.yaw) / w.heading_step_rad + w.half_h;
  if (!(std::isfinite(fx) && std::isfinite(fy) && std::isfinite(fj))) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  int64_t best = -1;
  for (int dj = 0; dj < 2; ++dj) {
    const double j = std::floor(fj) + dj;
    if (j < 0 || j >= w.sizeH()) continue;
    for (int dy = 0; dy < 2; ++dy) {
      const double ty = std::floor(fy) + dy;
      if (ty < 0 || ty >= w.sizeY()) continue;
      for (int dx = 0; dx < 2; ++dx) {
        const double tx = std::floor(fx) + dx;
        if (tx < 0 || tx >= w.sizeX()) continue;
        best = std::max(best, problem.score(static_cast<int>(j), 0, static_cast<int>(tx),
                                            static_cast<int>(ty)));
      }
    }
  }
  if (best < 0) return std::numeric_limits<double>::quiet_NaN();
  const ScoreQuantizer q(problem.map().options());
  return static_cast<double>(optimum.score - best) * q.step() /
         static_cast<double>(std::max<int64_t>(1, problem.scanPoints()));
}

}  // namespace

RegistrationResult<PreparedSearch> Registration::prepare(const ChunkMap& map,
                                                         const PointList& base_points,
                                                         const MatchRequest& request) const {
  using R = RegistrationResult<PreparedSearch>;
  const std::string invalid = options_.validate();
  if (!invalid.empty()) {
    return R::failure(RegistrationError::kInvalidOptions, "registration options: " + invalid);
  }
  if (!finitePose(request.prior)) {
    return R::failure(RegistrationError::kInvalidPrior, "prior pose is not finite");
  }
  FilteredScan f =
      filterScan(base_points, request.prior.roll, request.prior.pitch, options_.filter);
  if (f.points.empty()) {
    return R::failure(RegistrationError::kNoPoints,
                      "no points left after filtering: " + std::to_string(f.input_points) +
                          " input, " + std::to_string(f.dropped_nonfinite) + " non-finite, " +
                          std::to_string(f.dropped_range) + " out of range, " +
                          std::to_string(f.dropped_height) + " out of the height band");
  }
  // Height pre-alignment, then the window over x, y, heading around the (raised) prior.
  Pose6 prior = request.prior;
  const double z_offset = bestHeightOffset(map, f.points, prior, options_.z_search_m);
  prior.z += z_offset;
  const SearchWindow window =
      SearchWindow::fromExtent(prior, request.half_x_m, request.half_y_m, request.half_heading_rad,
                               options_.heading_step_rad, map.geometry().resolution_m);
  // SearchProblem::create validates the window first (same message), then fails only when no
  // chunk lies under the window (the points are not empty here): the window is checked here so
  // that each failure gets its kind.
  const std::string bad_window = window.validate();
  if (!bad_window.empty()) {
    return R::failure(RegistrationError::kInvalidWindow, "search window: " + bad_window);
  }
  // The fused method's ground returns: filtered as the reflectivity layer's (levelled already).
  FilteredScan ground;
  SecondChannel second;
  if (request.fused != nullptr) {
    if (request.fused->map == nullptr) {
      return R::failure(RegistrationError::kInvalidOptions,
                        "fused method: no reflectivity map given");
    }
    const std::string incompatible = channelCompatibility(map, *request.fused->map);
    if (!incompatible.empty()) {
      return R::failure(RegistrationError::kInvalidOptions,
                        "fused method: the height and reflectivity maps cannot be searched "
                        "together: " +
                            incompatible);
    }
    ground = filterScan(request.fused->points, 0.0, 0.0,
                        reflectivityRegistrationOptions(options_).filter);
    if (ground.points.empty()) {
      return R::failure(RegistrationError::kNoPoints,
                        "fused method: no ground returns left after filtering (" +
                            std::to_string(request.fused->points.size()) + " given)");
    }
    second = {request.fused->map, &ground.points};
  }
  if (searchesGlobally(window) && options_.global.max_points > 0) {
    f.points = thinEvenly(f.points, options_.global.max_points);
    ground.points = thinEvenly(ground.points, options_.global.max_points);
  }
  auto problem = SearchProblem::create(map, f.points, window, pool_.get(),
                                       request.fused != nullptr ? &second : nullptr);
  if (!problem.ok()) return R::failure(RegistrationError::kOffMap, problem.error());
  return PreparedSearch{std::move(f), z_offset, std::move(problem.value()), std::move(ground)};
}

RegistrationResult<MatchResult> Registration::match(const ChunkMap& map,
                                                    const PointList& base_points,
                                                    const MatchRequest& request,
                                                    std::vector<TraversalNode>* traversal,
                                                    const std::function<double()>& now,
                                                    RegistrationTiming* timing) const {
  auto tick = [&]() { return now ? now() : 0.0; };
  const double t0 = tick();
  auto prepared = prepare(map, base_points, request);
  if (!prepared.ok()) {
    return RegistrationResult<MatchResult>::failure(prepared.errorKind(), prepared.error());
  }
  const double t1 = tick();
  bool complete = true, cancelled = false, below_floor = false;
  SearchOutcome best =
      search(prepared->problem, traversal, &complete, request.cancel, &cancelled, &below_floor);
  if (timing) {
    timing->filter_s = t1 - t0;
    timing->search_s = tick() - t1;
  }
  if (cancelled) {
    return RegistrationResult<MatchResult>::failure(
        RegistrationError::kCancelled,
        "global search cancelled after " + std::to_string(best.stats.evaluations) +
            " node scores: a newer pose replaced the one it searched around");
  }
  if (below_floor) {
    char floor[32];
    std::snprintf(floor, sizeof(floor), "%.2f", options_.global.min_score_per_point);
    return RegistrationResult<MatchResult>::failure(
        RegistrationError::kBelowFloor,
        std::string("no pose of the window scores the global search's floor of ") + floor +
            " nats per point (global/min_score_per_point), proved after " +
            std::to_string(best.stats.evaluations) +
            " node scores: the vehicle is not in this window");
  }
  if (!complete) {
    return RegistrationResult<MatchResult>::failure(
        RegistrationError::kSearchBudget,
        "search stopped at its budget of " + std::to_string(options_.global.max_evaluations) +
            " node scores before proving an optimum (window of " +
            std::to_string(prepared->problem.window().poses()) + " poses)");
  }
  return finish(map, base_points, request, std::move(prepared.value()), std::move(best), now,
                timing);
}

SearchOutcome Registration::search(const SearchProblem& problem,
                                   std::vector<TraversalNode>* traversal, bool* complete,
                                   const std::atomic<bool>* cancel, bool* cancelled,
                                   bool* below_floor) const {
  if (complete != nullptr) *complete = true;
  if (cancelled != nullptr) *cancelled = false;
  if (below_floor != nullptr) *below_floor = false;
  // Algorithm 2 (reference) or 3 over x, y, heading; wide heading ranges over intervals.
  if (options_.exhaustive) return exhaustiveSearch(problem);
  if (searchesGlobally(problem.window())) {
    GlobalSearchOutcome g =
        globalBranchAndBound(problem, options_.global, global_pool_.get(), cancel);
    if (complete != nullptr) *complete = g.complete;
    if (cancelled != nullptr) *cancelled = g.cancelled;
    if (below_floor != nullptr) *below_floor = g.below_floor;
    return std::move(g.best);
  }
  return branchAndBoundSearch(problem, options_.branch_and_bound, traversal, pool_.get());
}

RegistrationResult<MatchResult> Registration::finish(const ChunkMap& map,
                                                     const PointList& base_points,
                                                     const MatchRequest& request,
                                                     PreparedSearch prepared, SearchOutcome search,
                                                     const std::function<double()>& now,
                                                     RegistrationTiming* timing) const {
  if (searchesGlobally(prepared.problem.window())) {
    return finishGlobal(map, base_points, request, std::move(prepared), std::move(search), now,
                        timing);
  }
  return finishLocal(map, base_points, request, std::move(prepared), std::move(search), now,
                     timing);
}

RegistrationResult<MatchResult> Registration::finishGlobal(
    const ChunkMap& map, const PointList& base_points, const MatchRequest& request,
    PreparedSearch prepared, SearchOutcome search, const std::function<double()>& now,
    RegistrationTiming* timing) const {
  using R = RegistrationResult<MatchResult>;
  auto tick = [&]() { return now ? now() : 0.0; };
  const double t0 = tick();
  MatchCertificate global_certificate;
  if (options_.certificate.enabled) {
    bool cancelled = false;
    global_certificate =
        certifyGlobalOptimum(prepared.problem, search, options_.certificate, options_.global,
                             global_pool_.get(), request.cancel, &cancelled);
    if (cancelled) {
      return R::failure(RegistrationError::kCancelled,
                        "global certificate cancelled after " +
                            std::to_string(global_certificate.evaluations) +
                            " node scores: a newer pose replaced the one it searched around");
    }
  }
  const double t1 = tick();
  // The confirming search: the tracking search around the global optimum, on all points.
  MatchRequest confirm = request;
  confirm.prior.x = search.pose.x;
  confirm.prior.y = search.pose.y;
  confirm.prior.yaw = search.pose.yaw;
  confirm.half_x_m = confirm.half_y_m = options_.global.confirm_half_xy_m;
  confirm.half_heading_rad = options_.global.confirm_half_heading_rad;
  auto local = prepare(map, base_points, confirm);
  if (!local.ok()) return R::failure(local.errorKind(), "confirming search: " + local.error());
  SearchOutcome confirm_search = this->search(local->problem, nullptr);
  const double t2 = tick();
  auto r = finishLocal(map, base_points, confirm, std::move(local.value()),
                       std::move(confirm_search), now, timing);
  if (!r.ok()) return r;
  if (timing) {
    timing->search_s += t2 - t1;
    timing->certificate_s += t1 - t0;
  }
  MatchResult& out = r.value();
  out.global = true;
  out.confirm_search = std::move(out.search);
  out.global_certificate = global_certificate;
  out.search = std::move(search);
  out.search.dropCertificateMemos();
  out.search.stats.evaluations += out.confirm_search.stats.evaluations;
  MatchCertificate& c = out.certificate;
  if (!global_certificate.certified && c.failure != CertificateFailure::kDisabled) {
    c.certified = false;
    c.failure = global_certificate.failure;
  }
  c.evaluations += global_certificate.evaluations;
  // Every plausible pose of the global proof lies within its protection of the global
  // optimum, which lies a cell's diagonal and a heading step from the grid (as for the
  // confirming search), and the published pose this far from it.
  const Protection global =
      protectionOf(global_certificate, out.search.pose, out.pose, map.geometry().resolution_m,
                   prepared.problem.window().heading_step_rad);
  out.protection_xy_m = std::max(out.protection_xy_m, global.xy_m);
  out.protection_heading_rad = std::max(out.protection_heading_rad, global.heading_rad);
  return r;
}

RegistrationResult<MatchResult> Registration::finishLocal(
    const ChunkMap& map, const PointList& base_points, const MatchRequest& request,
    PreparedSearch prepared, SearchOutcome search, const std::function<double()>& now,
    RegistrationTiming* timing) const {
  using R = RegistrationResult<MatchResult>;
  auto tick = [&]() { return now ? now() : 0.0; };
  const double t2 = tick();
  MatchResult out;
  out.search = std::move(search);
  out.z_offset_m = prepared.z_offset_m;
  out.filtered = std::move(prepared.filtered);
  const FilteredScan& f = out.filtered;
  // Constrained 6-DOF hill climb on the exact likelihood, on the unlevelled points.
  const Eigen::Matrix3f unlevel =
      (Eigen::AngleAxisd(request.prior.pitch, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(request.prior.roll, Eigen::Vector3d::UnitX()))
          .toRotationMatrix()
          .transpose()
          .cast<float>();
  PointList refine_points = thinEvenly(f.voxels, options_.refine_max_points);
  for (Eigen::Vector3f& p : refine_points) p = unlevel * p;
  double reach = 0.0;
  for (const Eigen::Vector3f& p : refine_points) reach = std::max<double>(reach, p.norm());
  const ExactScorer scorer(map, map.options().ll_floor, out.search.pose.x, out.search.pose.y,
                           reach + 2.0);
  HillClimbOptions hc = options_.hill_climb;
  hc.max_yaw_rad = std::max(hc.max_yaw_rad, options_.heading_step_rad);
  hc.max_xy_m = std::max(hc.max_xy_m, map.geometry().resolution_m);
  size_t refined = refine_points.size();
  if (request.fused != nullptr) {  // the sum of both exact likelihoods (fused_channel.h)
    const PointList ground = thinEvenly(prepared.ground.voxels, options_.refine_max_points);
    double ground_reach = 0.0;
    for (const Eigen::Vector3f& p : ground) {
      ground_reach = std::max<double>(ground_reach, p.head<2>().norm());
    }
    const ChunkMap& ground_map = *request.fused->map;
    const ExactScorer ground_scorer(ground_map, ground_map.options().ll_floor, out.search.pose.x,
                                    out.search.pose.y, ground_reach + 2.0);
    out.refinement = fusedHillClimb(scorer, refine_points, ground_scorer, ground, out.search.pose,
                                    hc, pool_.get());
    refined += ground.size();
  } else {
    out.refinement = hillClimb(scorer, refine_points, out.search.pose, hc, pool_.get());
  }
  out.pose = out.refinement.pose;
  out.pose.yaw = wrapAngle(out.pose.yaw);
  out.log_likelihood_per_point =
      out.refinement.score / static_cast<double>(std::max<size_t>(1, refined));
  double t3 = tick();
  if (timing) timing->refine_s = t3 - t2;

  out.covariance_detail =
      searchCovariance(prepared.problem, out.search, options_.covariance, pool_.get());
  out.covariance_xyh = out.covariance_detail.covariance;
  const double t3c = tick();
  if (timing) timing->covariance_s = t3c - t3;
  CertificateOptions certificate = options_.certificate;
  certificate.max_evaluations = certificate.budgetFor(request.half_x_m, request.half_y_m);
  out.certificate = certifyOptimum(prepared.problem, out.search, certificate, pool_.get());
  out.search.dropCertificateMemos();  // what the search kept for the proof: done with
  {
    const Protection p =
        protectionOf(out.certificate, out.search.pose, out.pose, map.geometry().resolution_m,
                     prepared.problem.window().heading_step_rad);
    out.protection_xy_m = p.xy_m;
    out.protection_heading_rad = p.heading_rad;
  }
  if (request.has_reference) {
    out.reference_deficit_per_point =
        referenceDeficitPerPoint(prepared.problem, out.search, request.reference);
  }
  const double t4 = tick();
  if (timing) timing->certificate_s = t4 - t3c;

  // Map coverage at the result: share of search points over non-empty cells.
  {
    const Eigen::Isometry3d T = toIsometry(out.pose);
    size_t covered = 0;
    for (const Eigen::Vector3f& p : refine_points) {
      const Eigen::Vector3d m = T * p.cast<double>();
      const GaussianMixture1D* g = map.mixture(map.geometry().cellAt(m.x(), m.y()));
      covered += (g != nullptr && !g->empty()) ? 1 : 0;
    }
    out.map_coverage = static_cast<double>(covered) / refine_points.size();
  }
  if (out.map_coverage < options_.min_map_coverage) {
    return R::failure(RegistrationError::kLowCoverage,
                      "only " + std::to_string(static_cast<int>(100 * out.map_coverage)) +
                          "% of the scan lies over mapped cells at the best pose (minimum " +
                          std::to_string(static_cast<int>(100 * options_.min_map_coverage)) +
                          "%): vehicle off the map or map not loaded");
  }
  if (!finitePose(out.pose) || !out.covariance_xyh.allFinite()) {
    return R::failure(RegistrationError::kNumerical,
                      "numerical failure: non-finite pose or covariance");
  }
  if (options_.classify_obstacles) {
    out.obstacles = classifyObstacles(map, base_points, out.pose, options_.obstacles, pool_.get());
  }
  if (timing) timing->obstacles_s = tick() - t4;
  return out;
}

}  // namespace gmm_localization
