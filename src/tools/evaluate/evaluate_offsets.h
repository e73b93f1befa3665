#pragma once
// The registration experiment of paper V-A / Fig. 8: for a subset of scans, search the paper's
// window (the policy's wide window, 25 m x 25 m x +-15 deg by default) around the ground truth
// moved by a random offset within radius_m and +-max_heading_rad, and measure how far the
// result lands from the truth. Runs on its own worker thread (the matcher is const and
// thread-safe), so the bag pass and the trials share the two cores. The first scan also gets
// one extra search, with a fixed offset, whose branch-and-bound traversal makes Fig. 9.

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/matching/traversal_image.h"

namespace gmm_localization {
namespace eval {

struct OffsetOptions {
  int trials_per_scan = 1;
  double radius_m = 10.0;
  double max_heading_rad = 15.0 * M_PI / 180.0;
  uint64_t seed = 1;
  size_t max_queue = 3;  ///< scans waiting for the worker (bounds memory; the producer waits)
  /// The Fig. 9 search (on the first scan, not counted in the rows): an offset that keeps the
  /// optimum well inside the window so that all slices around it exist.
  PlanarOffset figure_offset{3.0, -2.0, 3.0 * M_PI / 180.0};
};

/// Fig. 9 material: the traversal picture of one search, as 11 heading slices every 3 steps
/// around the optimum (like the paper), plus what is needed to label it.
struct TraversalFigure {
  TraversalImage image;
  int layers = 0;               ///< rows: top layer .. 0
  int heading_step_offset = 3;  ///< columns are headings opt + k * this, k = -5..5
  double heading_step_rad = 0.0;
  double half_x_m = 0.0;
  int64_t evaluations = 0, exhaustive_poses = 0;
  double search_ms = 0.0;
  double stamp_s = 0.0;
};

class OffsetExperiment {
 public:
  /// `reflectivity_map`: the fused method's second map (null for the other methods).
  OffsetExperiment(const MatchProcessor& processor, std::shared_ptr<const ChunkMap> map,
                   const OffsetOptions& options, std::function<double()> clock,
                   std::shared_ptr<const ChunkMap> reflectivity_map = nullptr);
  ~OffsetExperiment();

  /// Queues `trials_per_scan` registrations of `scan` (base_link, not deskewed) around the true
  /// pose `truth` (full 6-DOF: z, roll, pitch from the truth). twist: deskewing, as the matcher.
  void submit(const ScanInput& scan, const Pose6& truth, std::optional<BodyTwist> twist);
  /// Waits for the queue to drain and returns the rows in submission order.
  std::vector<OffsetRow> finish();
  /// The first trial's traversal (empty image when none was recorded).
  const TraversalFigure& traversal() const { return figure_; }

 private:
  struct Job {
    ScanInput scan;
    Pose6 truth;
    std::optional<BodyTwist> twist;
    std::vector<PlanarOffset> offsets;
    bool want_traversal = false;
  };
  void loop();
  void run(Job& job);

  const MatchProcessor& processor_;
  std::shared_ptr<const ChunkMap> map_;
  std::shared_ptr<const ChunkMap> reflectivity_map_;
  OffsetOptions options_;
  std::function<double()> clock_;
  OffsetSampler sampler_;
  bool traversal_requested_ = false;

  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  bool busy_ = false, stop_ = false;
  std::vector<OffsetRow> rows_;
  TraversalFigure figure_;
  std::thread worker_;
};

/// Writes an RGB image as binary PPM (P6). Throws std::runtime_error when it cannot.
void writePpm(const TraversalImage& image, const std::string& path);

}  // namespace eval
}  // namespace gmm_localization
