// Diagnostics of the map server: the map and its tiles, the chunks, the vehicle's position.
#include <diagnostic_msgs/DiagnosticStatus.h>

#include <cstdio>

#include "gmm_localization/core/common/input_watchdog.h"
#include "gmm_localization/ros/map_server.h"

namespace gmm_localization {
namespace node {
namespace {

using diagnostic_msgs::DiagnosticStatus;

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", s);
  return buf;
}

std::string tileName(const TileId& t) {
  return "(" + std::to_string(t.x) + ", " + std::to_string(t.y) + ")";
}

}  // namespace

void MapServer::setUpDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);

  diagnostics_->add("map", [this](StatusBuilder& s) {
    const ChunkEngineStats st = engine_->stats();
    const MapSummary m = engine_->mapSummary();
    s.add("map directory", st.map_directory);
    s.add("map version", std::to_string(st.map_version));
    s.add("tiles in map", st.tiles_in_map);
    s.add("tiles loaded", st.tiles_cached);
    s.add("last tile load [ms]", st.last_tile_load_ms);
    s.add("extent x [m]", std::to_string(m.min_x_m) + " .. " + std::to_string(m.max_x_m));
    s.add("extent y [m]", std::to_string(m.min_y_m) + " .. " + std::to_string(m.max_y_m));
    s.add("tile load errors", st.tile_errors.size());
    s.add("chunks served without a bad tile", st.chunks_degraded);
    if (!st.tile_errors.empty()) {
      std::string names;
      size_t shown = 0;
      for (const auto& [tile, why] : st.tile_errors) {
        s.add("bad tile " + tileName(tile), why);
        if (shown++ < 4) names += (names.empty() ? "" : ", ") + tileName(tile);
      }
      if (st.tile_errors.size() > shown) names += ", ...";
      s.summary(DiagnosticStatus::ERROR,
                std::to_string(st.tile_errors.size()) +
                    " tile(s) failed to load and are served as empty (retried every " +
                    seconds(options_.engine.tile_retry_period_s) + " s): " + names);
    } else {
      s.summary(DiagnosticStatus::OK, "map loaded");
    }
  });

  diagnostics_->add("chunks", [this](StatusBuilder& s) {
    const ChunkEngineStats st = engine_->stats();
    s.add("chunks held", st.chunks_held);
    s.add("chunks pending", st.chunks_pending);
    s.add("chunks in progress", st.chunks_in_progress);
    s.add("raster memory [MB]", static_cast<double>(st.raster_bytes) / 1048576.0);
    s.add("chunks rasterized", std::to_string(st.chunks_rasterized));
    s.add("last rasterization [ms]", st.last_raster_ms);
    s.add("mean rasterization [ms]", st.mean_raster_ms);
    s.add("max rasterization [ms]", st.max_raster_ms);
    s.add("raster radius [m]", options_.engine.raster_radius_m);
    s.summary(DiagnosticStatus::OK, st.chunks_pending > 0 ? "rasterizing" : "up to date");
  });

  // The console line of a map that does not cover the vehicle: its own throttle (wall time).
  diagnostics_->add("vehicle position", [this,
                                         line = LineThrottle(30.0)](StatusBuilder& s) mutable {
    CentreSelection where;
    std::string tf_error;
    {
      std::lock_guard<std::mutex> lock(position_mutex_);
      where = centres_;
      tf_error = tf_error_;
    }
    s.add("source", where.source);
    if (!tf_error.empty()) s.add("TF error", tf_error);
    if (where.centres.empty()) {
      s.summary(DiagnosticStatus::WARN, "no vehicle position yet (no TF " + options_.map_frame +
                                            " -> " + options_.base_frame +
                                            ", no pose_hint, no initial_position)");
      return;
    }
    const MapSummary m = engine_->mapSummary();
    const PlanCentre* outside = nullptr;
    for (size_t i = 0; i < where.centres.size(); ++i) {
      const PlanCentre& c = where.centres[i];
      s.add("x [m] #" + std::to_string(i), c.x());
      s.add("y [m] #" + std::to_string(i), c.y());
      if (outside == nullptr &&
          (c.x() < m.min_x_m || c.x() > m.max_x_m || c.y() < m.min_y_m || c.y() > m.max_y_m)) {
        outside = &c;
      }
    }
    if (outside != nullptr) {
      s.summary(DiagnosticStatus::WARN, "vehicle position outside the map extent");
      if (line.due(ros::WallTime::now().toSec())) {
        ROS_WARN(
            "%s: the vehicle position (%.1f, %.1f) m from %s is outside the map's extent x "
            "[%.1f, %.1f], y [%.1f, %.1f] m: no map to match against. Either the map is not "
            "the one of this place (map_directory '%s', the launch argument map) or the pose is "
            "wrong (TF %s -> %s, /initialpose, initial_position): give a pose on the map on "
            "/initialpose",
            name_.c_str(), outside->x(), outside->y(), where.source.c_str(), m.min_x_m, m.max_x_m,
            m.min_y_m, m.max_y_m, engine_->stats().map_directory.c_str(),
            options_.map_frame.c_str(), options_.base_frame.c_str());
      }
    } else {
      line.reset();
      s.summary(DiagnosticStatus::OK, "position from " + where.source);
    }
  });
}

}  // namespace node
}  // namespace gmm_localization
