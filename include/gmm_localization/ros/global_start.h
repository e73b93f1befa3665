#pragma once
// The global start: a vehicle started with no pose at all finds itself on the map
// (launch/localization.launch global_start:=true). It sweeps the matcher's global window over
// the map (core/localization/start_sweep.h) until a match is accepted.
//
// Topics (relative; remap in launch):
//   map_index    gmm_localization/MapIndex in: the map (its directory: the tiles it holds, read
//                from the manifest; the chunks the map server holds now).
//   status       gmm_localization/MatchStatus in: the matcher's answers. prior_mode "no_prior"
//                for wait_s starts the sweep; an accepted match ends it.
//   initialpose  geometry_msgs/PoseWithCovarianceStamped in and out (remapped to /initialpose):
//                out, each window's centre with 3 sigma = window_half_xy_m and a heading sigma of
//                pi (the matcher searches its global window, the EKF starts there); in, a pose
//                from anyone else stands the sweep down.
//   region_hint  geometry_msgs/PoseWithCovarianceStamped out: the next window's centre, sent to
//                the map server first; the pose goes out once the index holds every chunk with
//                data of the window (or after map_wait_s).
// Diagnostics: "<name>: global start": state, window i of n and its centre, passes, windows
// searched (before all their chunks came, without an answer in time); WARN while it has no map,
// ERROR when it gave up (max_sweeps).

#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/core/localization/start_sweep.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/global_start_options.h"

namespace gmm_localization {
namespace node {

class GlobalStart {
 public:
  /// Throws ConfigError on a bad parameter.
  GlobalStart(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~GlobalStart();
  GlobalStart(const GlobalStart&) = delete;
  GlobalStart& operator=(const GlobalStart&) = delete;

 private:
  void onIndex(const MapIndex::ConstPtr& msg);
  void onStatus(const MatchStatus::ConstPtr& msg);
  void onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  void onTimer(const ros::WallTimerEvent&);
  /// A new map: its tiles (from the manifest in its directory, else the index's extent).
  void setMap(const MapIndex& index);
  /// Every chunk with data of the current window is in the last index.
  bool windowLoaded() const;
  geometry_msgs::PoseWithCovarianceStamped windowPose(const Eigen::Vector2d& centre,
                                                      const ros::Time& stamp) const;
  void setUpDiagnostics();

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  GlobalStartOptions options_;
  ros::Subscriber index_sub_, status_sub_, pose_sub_;
  ros::Publisher pose_pub_, hint_pub_;
  ros::WallTimer timer_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex mutex_;  // guards everything below
  StartSweep sweep_;
  std::string map_directory_;
  uint64_t map_version_ = 0;
  std::string tiles_source_;  ///< where the tiles came from (manifest or extent)
  std::unique_ptr<ChunkPlanner> planner_;
  std::set<ChunkId> held_;  ///< chunks in the last index
  std::vector<ChunkId> window_chunks_;
  std::optional<geometry_msgs::PoseWithCovarianceStamped> sent_;  ///< our last /initialpose
  uint64_t statuses_ = 0;
  ProblemLog problems_;  ///< its latest problem (WARN throttled)
};

}  // namespace node
}  // namespace gmm_localization
