#pragma once
// A start without any pose: global windows swept over the map until one holds the vehicle.
//
// The matcher's global search (core/matching/global_search.h) finds the vehicle anywhere inside
// a window of up to window/global_max_half_xy_m around a pose given on /initialpose with a
// coarse covariance, over the full turn of heading, and accepts the optimum only when it is
// certified (unique in the window). A vehicle that starts with no pose at all (no rviz click, no
// configured pose, no GNSS) is somewhere on the map: StartSweep walks it through such windows.
//
// The windows (sweepWindowCentres): squares of half extent h = window_half_xy_m on a regular
// grid over the bounding box of the map's tiles (or of those within region_radius_m of a rough
// fix), spaced at most 2 (h - m) apart with m = overlap_m / 2, the box grown by m on each side.
// So every point of every tile lies at least m inside some window (along each axis); m is the
// room for the vehicle's motion between the pose sent and the scan searched. Windows that
// overlap no tile are dropped; the rest are ordered by their distance from the centroid of the
// tiles' centres (or from the rough fix), nearest first, ties by position.
//
// The sequence (StartSweep, driven by the global start nodelet; every time in seconds of one
// monotonic clock, the caller's):
//   waiting    the matcher answers scans with no prior (MatchStatus prior_mode "no_prior");
//              once it has done so for wait_s, the first window is loaded;
//   loading    the map server is asked for the window's chunks (a pose hint); searched once
//              they are all held, or after map_wait_s anyway (counted);
//   searching  the window's centre is sent as /initialpose with 3 sigma = h and a heading
//              sigma of pi (the matcher's global window); the first global search centred
//              within window_half_xy_m / 4 of it (not one of the matcher's own around an
//              earlier window, which may still be running) that is not accepted, or
//              attempt_timeout_s without one, moves on to the next window; after the last window
//              the sweep starts over (the vehicle moves, and a search stopped at its node budget
//              may have missed it), up to max_sweeps passes (0: no limit), then gave_up;
//   localized  any accepted match (global or not) ends the work: the node stays idle, a later
//              loss is the matcher's (it widens its own global windows while lost);
//   stood_down a pose from anyone else on /initialpose (rviz, the GNSS initializer) before the
//              sweep ends: the matcher follows that pose (and its own global windows if it
//              is wrong).
// While waiting, an answer with a prior (a configured pose, an EKF posterior) restarts the wait:
// the sweep starts only after wait_s of answers without any.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/raster/chunk_planner.h"

namespace gmm_localization {

struct StartSweepOptions {
  double window_half_xy_m = 50.0;   ///< h: half extent of a window (matcher global_max_half_xy_m)
  double overlap_m = 10.0;          ///< neighbouring windows overlap by at least this [m]
  double wait_s = 5.0;              ///< matcher without a prior this long before the sweep starts
  double map_wait_s = 10.0;         ///< longest wait for a window's chunks before its search
  double attempt_timeout_s = 30.0;  ///< no answer from the window's search this long: next one
  int max_sweeps = 3;               ///< passes over the windows before giving up (0: no limit)
  /// A rough fix: only windows within region_radius_m of (region_x_m, region_y_m) are swept,
  /// nearest first. region_radius_m 0: the whole map.
  double region_x_m = 0.0, region_y_m = 0.0, region_radius_m = 0.0;

  bool hasRegion() const { return region_radius_m > 0.0; }
  /// Empty when valid, else which field is wrong.
  std::string validate() const;
};

/// Window centres covering the tiles (map-frame squares [m]); see the file comment. Empty when
/// no tile is given or none lies in the region.
std::vector<Eigen::Vector2d> sweepWindowCentres(const std::vector<Eigen::AlignedBox2d>& tiles,
                                                const StartSweepOptions& options);

/// The map-frame square [m] of every tile the map holds.
std::vector<Eigen::AlignedBox2d> tileSquares(const MapGeometry& geometry,
                                             const std::vector<TileId>& tiles);

/// Chunks with data (ChunkPlanner::hasData) whose square overlaps the window's, ascending.
std::vector<ChunkId> windowChunks(const ChunkPlanner& planner, const Eigen::Vector2d& centre,
                                  double half_xy_m);

class StartSweep {
 public:
  enum class State { kWaiting, kLoading, kSearching, kLocalized, kStoodDown, kGaveUp };
  static const char* stateName(State s);

  /// What the caller does now.
  struct Action {
    enum class Kind { kNone, kLoadMap, kSearch } kind = Kind::kNone;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< the window's centre [m]
    int window = -1;                                   ///< its index in windows()
  };

  explicit StartSweep(StartSweepOptions options);

  /// The windows to sweep (a new map): back to waiting unless localized, stood down or gave up.
  void setWindows(std::vector<Eigen::Vector2d> centres);
  const std::vector<Eigen::Vector2d>& windows() const { return windows_; }

  /// The matcher's answer to a scan.
  struct Answer {
    bool accepted = false;
    bool no_prior = false;                                    ///< its prior mode was "no_prior"
    bool global_search = false;                               ///< the window was global
    Eigen::Vector2d window_centre = Eigen::Vector2d::Zero();  ///< [m]
  };
  /// now_s: when the answer came.
  void onStatus(double now_s, const Answer& answer);
  /// Someone else gave a pose.
  void onExternalPose();
  /// The next step. map_loaded: every chunk of the window being loaded is held.
  Action poll(double now_s, bool map_loaded);

  State state() const { return state_; }
  const StartSweepOptions& options() const { return options_; }
  int window() const { return index_; }              ///< current window (-1 before the first)
  int sweeps() const { return sweeps_; }             ///< completed passes
  uint64_t searched() const { return searched_; }    ///< windows sent
  uint64_t searchedEarly() const { return early_; }  ///< ... before all their chunks came
  uint64_t timedOut() const { return timed_out_; }   ///< ... without an answer in time

 private:
  /// Enters `state` (loading or searching) for the current window: the caller's action.
  Action enter(State state, Action::Kind kind, double now_s);

  StartSweepOptions options_;
  std::vector<Eigen::Vector2d> windows_;
  State state_ = State::kWaiting;
  double no_prior_since_s_ = -1.0;  ///< first "no_prior" answer of the current run of them
  double phase_since_s_ = 0.0;      ///< start of loading or searching
  bool answered_ = false;           ///< the current window's global search came back rejected
  int index_ = -1;
  int sweeps_ = 0;
  uint64_t searched_ = 0, early_ = 0, timed_out_ = 0;
};

}  // namespace gmm_localization
