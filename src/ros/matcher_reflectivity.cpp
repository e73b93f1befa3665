// The fused method's second map layer (matcher.h): the reflectivity layer from a second map
// server on reflectivity/map_chunks and reflectivity/map_index, kept beside the height map, and
// why the two cannot be searched together (core channelCompatibility).
#include <string>

#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/ros/matcher.h"

namespace gmm_localization {
namespace node {

void Matcher::onReflectivityChunk(const ros::MessageEvent<const RasterChunk>& event) {
  const RasterChunk::ConstPtr msg = event.getConstMessage();
  std::string error;
  std::lock_guard<std::mutex> lock(map_mutex_);
  const auto verdict = reflectivity_client_.onChunk(event, &error);
  if (verdict == MapServerClient::ChunkVerdict::kInvalid) {
    ROS_WARN_THROTTLE(5.0, "%s: reflectivity chunk (%d, %d) rejected: %s", name_.c_str(),
                      msg->chunk_x, msg->chunk_y, error.c_str());
    return;
  }
  if (verdict == MapServerClient::ChunkVerdict::kAdded && reflectivity_client_.hasIndex()) {
    reflectivity_snapshot_ = std::make_shared<const ChunkMap>(reflectivity_client_.chunks());
  }
}

void Matcher::onReflectivityIndex(const ros::MessageEvent<const MapIndex>& event) {
  const MapIndex::ConstPtr msg = event.getConstMessage();
  std::lock_guard<std::mutex> lock(map_mutex_);
  const uint64_t previous = reflectivity_client_.mapVersion();
  std::string rejected;
  reflectivity_client_.onIndex(event, &rejected);
  if (!rejected.empty()) {
    ROS_WARN_THROTTLE(5.0,
                      "%s: reflectivity map index ignored (the current reflectivity layer stays "
                      "in use): %s",
                      name_.c_str(), rejected.c_str());
  } else if (reflectivity_client_.mapVersion() != previous) {
    ROS_INFO("%s: reflectivity layer: map version %lu ('%s'), %zu chunks listed", name_.c_str(),
             static_cast<unsigned long>(reflectivity_client_.mapVersion()),
             msg->map_directory.c_str(), msg->chunk_x.size());
  }
  reflectivity_snapshot_ = std::make_shared<const ChunkMap>(reflectivity_client_.chunks());
  checkLayers();
}

void Matcher::checkLayers() {
  std::string mismatch;
  if (map_client_.hasIndex() && reflectivity_client_.hasIndex()) {
    const std::string differ =
        channelCompatibility(map_client_.chunks(), reflectivity_client_.chunks());
    if (!differ.empty()) {
      mismatch = "the height map '" + map_client_.index()->map_directory +
                 "' and the reflectivity map '" + reflectivity_client_.index()->map_directory +
                 "' cannot be searched together: " + differ +
                 " (serve both with the same raster options, and build the reflectivity layer "
                 "from the height map's inputs: build_map --layer reflectivity --output "
                 "MAP/reflectivity)";
    }
  }
  if (!mismatch.empty() && mismatch != layer_mismatch_) {
    ROS_ERROR("%s: method fused: %s", name_.c_str(), mismatch.c_str());
  }
  layer_mismatch_ = mismatch;
}

std::string Matcher::reflectivityProblem() const {
  if (!layer_mismatch_.empty()) return layer_mismatch_;
  if (!reflectivity_client_.hasIndex()) {
    return "no reflectivity layer yet: nothing received on " + reflectivity_topic_ +
           " (the fused method needs MAP/reflectivity from the second map server, "
           "localization.launch method:=fused)";
  }
  if (!reflectivity_snapshot_ || reflectivity_snapshot_->size() == 0) {
    return "no reflectivity layer yet: no chunks received from " +
           reflectivity_client_.publisher() + " (" + reflectivity_topic_ + ")";
  }
  return {};
}

std::string Matcher::addReflectivityDiagnostics(StatusBuilder& s, bool* mismatch) {
  std::string problem;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    s.add("reflectivity layer: chunks held", reflectivity_client_.chunks().size());
    s.add("reflectivity layer: map version", reflectivity_client_.mapVersion());
    s.add("reflectivity layer: map directory",
          reflectivity_client_.hasIndex() ? reflectivity_client_.index()->map_directory : "");
    s.add("reflectivity layer: map server followed", reflectivity_client_.publisher());
    s.add("reflectivity layer: indices ignored (other publishers, invalid)",
          reflectivity_client_.ignoredIndices() + reflectivity_client_.rejectedIndices());
    problem = reflectivityProblem();
    *mismatch = !layer_mismatch_.empty();
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  s.add("scans skipped without a usable reflectivity layer", reflectivity_skips_);
  return problem;
}

}  // namespace node
}  // namespace gmm_localization
