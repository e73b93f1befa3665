#include "gmm_localization/ros/global_start.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <diagnostic_msgs/DiagnosticStatus.h>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/ros/gnss_conversion.h"
#include "gmm_localization/ros/map_server_client.h"

namespace gmm_localization {
namespace node {
namespace {

std::string centreText(const Eigen::Vector2d& c) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.1f, %.1f) m", c.x(), c.y());
  return text;
}

/// The tiles of the index's extent (a map whose manifest cannot be read here).
std::vector<TileId> extentTiles(const MapIndex& index, const MapGeometry& g) {
  std::vector<TileId> out;
  if (!(index.max_x_m > index.min_x_m) || !(index.max_y_m > index.min_y_m)) return out;
  const TileId lo = g.tileAt(index.min_x_m, index.min_y_m);
  const TileId hi = g.tileAt(index.max_x_m - 1e-6, index.max_y_m - 1e-6);
  for (int32_t x = lo.x; x <= hi.x; ++x) {
    for (int32_t y = lo.y; y <= hi.y; ++y) out.push_back({x, y});
  }
  return out;
}

}  // namespace

GlobalStart::GlobalStart(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : nh_(nh),
      pnh_(pnh),
      name_(name),
      options_(loadNodeletOptions(pnh, name, loadGlobalStartOptions)),
      sweep_(options_.sweep),
      problems_(name) {
  pose_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("initialpose", 2);
  hint_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("region_hint", 2);
  index_sub_ = nh_.subscribe("map_index", 4, &GlobalStart::onIndex, this);
  status_sub_ = nh_.subscribe("status", 20, &GlobalStart::onStatus, this);
  pose_sub_ = nh_.subscribe("initialpose", 4, &GlobalStart::onInitialPose, this);
  timer_ =
      nh_.createWallTimer(ros::WallDuration(options_.poll_period_s), &GlobalStart::onTimer, this);
  setUpDiagnostics();
  const StartSweepOptions& s = options_.sweep;
  ROS_INFO(
      "%s: with no pose for %.1f s, the matcher's global window (+-%.0f m, full turn) is swept "
      "over %s, up to %d pass(es)",
      name_.c_str(), s.wait_s, s.window_half_xy_m,
      s.hasRegion() ? ("the map within " + std::to_string(static_cast<int>(s.region_radius_m)) +
                       " m of " + centreText({s.region_x_m, s.region_y_m}))
                          .c_str()
                    : "the whole map",
      s.max_sweeps);
}

GlobalStart::~GlobalStart() {
  timer_.stop();
  index_sub_.shutdown();
  status_sub_.shutdown();
  pose_sub_.shutdown();
  diagnostics_.reset();  // its task reads members destroyed before it
}

void GlobalStart::setMap(const MapIndex& index) {
  const MapGeometry geometry = geometryOf(index);
  std::vector<TileId> tiles;
  auto store = MapStore::open(index.map_directory);
  if (store) {
    tiles = store->tileIds();
    tiles_source_ = "manifest";
  } else {
    tiles = extentTiles(index, geometry);
    tiles_source_ = "the index's extent (manifest not readable here: " + store.error() + ")";
    problems_.report("map '" + index.map_directory + "': " + tiles_source_);
  }
  std::sort(tiles.begin(), tiles.end());
  planner_ = std::make_unique<ChunkPlanner>(geometry, rasterOptionsOf(index), tiles);
  auto windows = sweepWindowCentres(tileSquares(geometry, tiles), options_.sweep);
  if (windows.empty()) {
    problems_.report("map '" + index.map_directory + "': no window to sweep (" +
                     (tiles.empty() ? std::string("no tile")
                                    : "no tile within region/radius_m of region/centre") +
                     ")");
  } else {
    ROS_INFO("%s: map '%s': %zu window(s) of +-%.0f m to sweep (tiles from the %s), first at %s",
             name_.c_str(), index.map_directory.c_str(), windows.size(),
             options_.sweep.window_half_xy_m, tiles_source_.c_str(),
             centreText(windows.front()).c_str());
  }
  sweep_.setWindows(std::move(windows));
  window_chunks_.clear();
}

void GlobalStart::onIndex(const MapIndex::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!planner_ || msg->map_directory != map_directory_ || msg->map_version != map_version_) {
    map_directory_ = msg->map_directory;
    map_version_ = msg->map_version;
    setMap(*msg);
  }
  held_.clear();
  const size_t n = std::min(msg->chunk_x.size(), msg->chunk_y.size());
  for (size_t i = 0; i < n; ++i) held_.insert({msg->chunk_x[i], msg->chunk_y[i]});
}

void GlobalStart::onStatus(const MatchStatus::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++statuses_;
  const auto before = sweep_.state();
  StartSweep::Answer a;
  a.accepted = msg->accepted;
  a.no_prior = msg->prior_mode == "no_prior";
  a.global_search = msg->global_search;
  a.window_centre = Eigen::Vector2d(msg->window_x_m, msg->window_y_m);
  sweep_.onStatus(wallNow(), a);
  if (before != StartSweep::State::kLocalized && sweep_.state() == StartSweep::State::kLocalized) {
    const auto& p = msg->pose.pose.position;
    ROS_INFO("%s: the matcher accepted a match at (%.2f, %.2f) m%s; the global start is idle",
             name_.c_str(), p.x, p.y,
             before == StartSweep::State::kWaiting
                 ? " before the sweep started"
                 : (" in window " + std::to_string(sweep_.window() + 1) + " of " +
                    std::to_string(sweep_.windows().size()))
                       .c_str());
  }
}

void GlobalStart::onInitialPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (sent_ && msg->header.stamp == sent_->header.stamp &&
      msg->pose.pose.position.x == sent_->pose.pose.position.x &&
      msg->pose.pose.position.y == sent_->pose.pose.position.y) {
    return;  // our own
  }
  const auto before = sweep_.state();
  sweep_.onExternalPose();
  if (sweep_.state() != before) {
    ROS_INFO("%s: a pose came on %s from elsewhere; the global start stands down", name_.c_str(),
             pose_sub_.getTopic().c_str());
  }
}

bool GlobalStart::windowLoaded() const {
  return std::all_of(window_chunks_.begin(), window_chunks_.end(),
                     [this](const ChunkId& id) { return held_.count(id) > 0; });
}

geometry_msgs::PoseWithCovarianceStamped GlobalStart::windowPose(const Eigen::Vector2d& centre,
                                                                 const ros::Time& stamp) const {
  GnssPoseEstimate e;  // a pose with its (x, y, yaw) covariance; the height unknown
  e.stamp_s = stamp.toSec();
  e.x_m = centre.x();
  e.y_m = centre.y();
  const double sigma_xy = options_.sweep.window_half_xy_m / 3.0;
  e.cov_xy_yaw =
      Eigen::Vector3d(sigma_xy * sigma_xy, sigma_xy * sigma_xy, M_PI * M_PI).asDiagonal();
  return initialPoseMsg(e, options_.map_frame);
}

void GlobalStart::onTimer(const ros::WallTimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto before = sweep_.state();
  const ros::Time stamp = ros::Time::now();
  const auto action = sweep_.poll(wallNow(), windowLoaded());
  const int n = static_cast<int>(sweep_.windows().size());
  if (action.kind == StartSweep::Action::Kind::kLoadMap) {
    window_chunks_ = planner_
                         ? windowChunks(*planner_, action.centre, options_.sweep.window_half_xy_m)
                         : std::vector<ChunkId>{};
    hint_pub_.publish(windowPose(action.centre, stamp));
    ROS_INFO("%s: no pose: window %d of %d (pass %d) at %s, loading its %zu chunks", name_.c_str(),
             action.window + 1, n, sweep_.sweeps() + 1, centreText(action.centre).c_str(),
             window_chunks_.size());
  } else if (action.kind == StartSweep::Action::Kind::kSearch) {
    sent_ = windowPose(action.centre, stamp);
    pose_pub_.publish(*sent_);
    ROS_INFO("%s: searching window %d of %d at %s (+-%.0f m, full turn)%s", name_.c_str(),
             action.window + 1, n, centreText(action.centre).c_str(),
             options_.sweep.window_half_xy_m,
             windowLoaded() ? "" : " before all its chunks came (map_wait_s)");
  } else if (before != StartSweep::State::kGaveUp && sweep_.state() == StartSweep::State::kGaveUp) {
    problems_.report(
        "no match accepted in " + std::to_string(sweep_.sweeps()) + " passes over " +
        std::to_string(n) +
        " windows: giving up (max_sweeps); give a pose in rviz or check the map and the scans");
  }
}

void GlobalStart::setUpDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  diagnostics_->add("global start", [this](StatusBuilder& s) {
    using diagnostic_msgs::DiagnosticStatus;
    std::lock_guard<std::mutex> lock(mutex_);
    const auto state = sweep_.state();
    const int n = static_cast<int>(sweep_.windows().size());
    s.add("state", StartSweep::stateName(state));
    s.add("map", map_directory_.empty() ? std::string("no map index yet") : map_directory_);
    s.add("tiles from", tiles_source_);
    s.add("windows", n);
    s.add("window half extent [m]", options_.sweep.window_half_xy_m);
    if (sweep_.window() >= 0 && sweep_.window() < n) {
      s.add("current window", std::to_string(sweep_.window() + 1) + " at " +
                                  centreText(sweep_.windows()[sweep_.window()]));
    }
    s.add("passes completed", sweep_.sweeps());
    s.add("windows searched", sweep_.searched());
    s.add("searched before all their chunks came", sweep_.searchedEarly());
    s.add("searches without an answer in time", sweep_.timedOut());
    s.add("matcher answers received", statuses_);
    if (state == StartSweep::State::kGaveUp) {
      s.summary(DiagnosticStatus::ERROR, "gave up (max_sweeps): " + problems_.last());
    } else if (map_directory_.empty()) {
      s.summary(DiagnosticStatus::WARN, "no map index yet (is the map server running?)");
    } else if (problems_.recent()) {
      s.summary(DiagnosticStatus::WARN, problems_.last());
    } else {
      s.summary(DiagnosticStatus::OK, StartSweep::stateName(state));
    }
  });
}

}  // namespace node
}  // namespace gmm_localization
