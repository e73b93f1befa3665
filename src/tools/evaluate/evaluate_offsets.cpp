#include "evaluate/evaluate_offsets.h"
#include "evaluate/evaluate_integrity.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "gmm_localization/core/localization/match_policy.h"

namespace gmm_localization {
namespace eval {
namespace {

/// The paper's Fig. 9 shows 11 heading slices, every third heading around the optimum.
constexpr int kSlices = 11;
constexpr int kSliceStep = 3;

TraversalFigure paperStyleFigure(const MatchReport& r) {
  TraversalFigure f;
  const SearchOutcome& opt = r.result.search;
  const int centre = kSlices / 2;
  std::vector<TraversalNode> nodes;
  for (TraversalNode n : r.traversal) {
    const int d = n.heading_index - opt.heading_index;
    if (d % kSliceStep != 0 || std::abs(d / kSliceStep) > centre) continue;
    n.heading_index = static_cast<int16_t>(d / kSliceStep + centre);
    nodes.push_back(n);
  }
  SearchWindow w = r.search_window;
  w.half_h = centre;
  SearchOutcome o = opt;
  o.heading_index = centre;
  TraversalImageOptions io;
  io.max_tile_px = 160;
  io.gap_px = 3;
  io.max_width_px = kSlices * io.max_tile_px + (kSlices - 1) * io.gap_px;
  f.image = renderTraversal(nodes, w, opt.stats.top_layer, o, io);
  f.layers = opt.stats.top_layer + 1;
  f.heading_step_offset = kSliceStep;
  f.heading_step_rad = r.search_window.heading_step_rad;
  f.half_x_m = r.window.half_x_m;
  f.evaluations = opt.stats.evaluations;
  f.exhaustive_poses = opt.stats.exhaustive_poses;
  f.search_ms = r.timing.search_s * 1000.0;
  f.stamp_s = r.stamp_s;
  return f;
}

}  // namespace

OffsetExperiment::OffsetExperiment(const MatchProcessor& processor,
                                   std::shared_ptr<const ChunkMap> map,
                                   const OffsetOptions& options, std::function<double()> clock,
                                   std::shared_ptr<const ChunkMap> reflectivity_map)
    : processor_(processor),
      map_(std::move(map)),
      reflectivity_map_(std::move(reflectivity_map)),
      options_(options),
      clock_(std::move(clock)),
      sampler_(options.seed, options.radius_m, options.max_heading_rad) {
  worker_ = std::thread([this]() { loop(); });
}

OffsetExperiment::~OffsetExperiment() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void OffsetExperiment::submit(const ScanInput& scan, const Pose6& truth,
                              std::optional<BodyTwist> twist) {
  Job job;
  job.scan = scan;
  job.truth = truth;
  job.twist = twist;
  // Offsets are drawn here, in submission order: the same seed gives the same trials.
  for (int k = 0; k < options_.trials_per_scan; ++k) job.offsets.push_back(sampler_.next());
  job.want_traversal = !traversal_requested_;
  traversal_requested_ = true;
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this]() { return queue_.size() < options_.max_queue; });
  queue_.push_back(std::move(job));
  changed_.notify_all();
}

std::vector<OffsetRow> OffsetExperiment::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this]() { return queue_.empty() && !busy_; });
  return rows_;
}

void OffsetExperiment::loop() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this]() { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop requested and nothing left
      job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    changed_.notify_all();
    run(job);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    changed_.notify_all();
  }
}

namespace {

MatchReport searchFrom(const MatchProcessor& processor, const ChunkMap& map, const ScanInput& scan,
                       const Pose6& truth, const PlanarOffset& off,
                       const std::optional<BodyTwist>& twist, bool want_traversal,
                       const std::function<double()>& clock, const ChunkMap* reflectivity_map) {
  Prior prior;
  prior.source = PriorSource::kConfigured;
  prior.pose = truth;
  prior.pose.x += off.dx_m;
  prior.pose.y += off.dy_m;
  prior.pose.yaw = wrapAngle(prior.pose.yaw + off.dyaw_rad);
  prior.wide = true;  // the policy's wide window: the paper's 25 m x 25 m x +-15 deg
  prior.z_known = true;
  ScanInput with_truth = scan;
  with_truth.has_reference = true;
  with_truth.reference = truth;
  return processor.process(map, std::move(with_truth), prior, twist ? &*twist : nullptr,
                           want_traversal, clock, reflectivity_map);
}

}  // namespace

void OffsetExperiment::run(Job& job) {
  if (job.want_traversal) {
    const MatchReport r = searchFrom(processor_, *map_, job.scan, job.truth, options_.figure_offset,
                                     job.twist, true, clock_, reflectivity_map_.get());
    if (r.has_result && !r.traversal.empty()) {
      TraversalFigure f = paperStyleFigure(r);
      std::lock_guard<std::mutex> lock(mutex_);
      figure_ = std::move(f);
    }
  }
  std::vector<OffsetRow> rows;
  for (const PlanarOffset& off : job.offsets) {
    const MatchReport r = searchFrom(processor_, *map_, job.scan, job.truth, off, job.twist, false,
                                     clock_, reflectivity_map_.get());
    OffsetRow row;
    row.stamp_s = job.scan.stamp_s;
    row.offset = off;
    row.has_result = r.has_result;
    row.accepted = r.accepted();
    row.reason = r.reason;
    if (r.has_result) {
      const Pose6& p = r.result.pose;
      row.error_m = std::hypot(p.x - job.truth.x, p.y - job.truth.y);
      row.error_yaw_rad = wrapAngle(p.yaw - job.truth.yaw);
      row.evaluations = static_cast<uint64_t>(r.result.search.stats.evaluations);
      row.search_fraction = r.result.search.stats.fraction();
      row.integrity = integrityOf(r.result);
      row.integrity.certificate_ms = r.timing.certificate_s * 1000.0;
    }
    row.search_ms = r.timing.search_s * 1000.0;
    row.total_ms = r.total_s * 1000.0;
    rows.push_back(row);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  rows_.insert(rows_.end(), rows.begin(), rows.end());
}

void writePpm(const TraversalImage& image, const std::string& path) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "P6\n" << image.width << " " << image.height << "\n255\n";
  f.write(reinterpret_cast<const char*>(image.rgb.data()),
          static_cast<std::streamsize>(image.rgb.size()));
  if (!f) throw std::runtime_error("cannot write " + path);
}

}  // namespace eval
}  // namespace gmm_localization
