// Matcher health on /diagnostics (matcher.h): scan and match rates, accepted share, last score
// per point, certified share and last certificate, search time, window, chunks held, dropped scans,
// prior mode and last reason; the scan topic's rate and stamp checks; and the console lines
// that name the fix of a silent scan topic, a missing prior and an initial pose that is never
// matched.
#include <cmath>
#include <cstdio>

#include "gmm_localization/ros/matcher.h"

namespace gmm_localization {
namespace node {

void Matcher::record(const MatchReport& r, uint32_t dropped) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++scans_;
  const double now_s = ros::WallTime::now().toSec();
  if (r.accepted()) {
    ++accepted_;
    inputs_.heard(matches_input_, now_s);
  }
  acquisition_.onScan(r.prior.explicit_generation, r.outcome, r.window.half_x_m);
  if (r.outcome != MatchOutcome::kSkipped && r.prior.explicit_generation != 0) {
    acquisition_source_ = priorSourceName(r.prior.source);
  }
  if (acquisition_.due(now_s)) warnStuck(r);
  recent_accepted_.push_back(r.accepted());
  while (recent_accepted_.size() > 50) recent_accepted_.pop_front();
  if (r.accepted()) {
    const MatchCertificate& c = r.result.certificate;
    recent_certified_.push_back(c.certified);
    while (recent_certified_.size() > 50) recent_certified_.pop_front();
    certified_ += c.certified ? 1 : 0;
    last_certificate_ = c.certified ? "certified" : certificateFailureName(c.failure);
    last_protection_xy_m_ = c.protection_xy_m;
    last_separation_ = c.separation_per_point;
  }
  last_reason_ = r.accepted() ? "" : r.reason;
  if (r.has_result) last_ll_per_point_ = r.result.log_likelihood_per_point;
  if (r.outcome != MatchOutcome::kSkipped) {
    last_search_ms_ = 1e3 * r.timing.search_s;
    last_total_ms_ = 1e3 * r.total_s;
    last_window_ = r.window;
  }
  last_prior_source_ = priorSourceName(r.prior.source);
}

void Matcher::warnStuck(const MatchReport& r) {
  const PriorSource source = r.prior.source;
  const Pose6& p = r.prior.pose;
  const int lost_after = options_.policy.relocalization.lost_after_rejections;
  const double global_m = options_.policy.window.global_max_half_xy_m;
  char searched[320];
  if (r.prior.lost) {
    std::snprintf(searched, sizeof(searched),
                  "the global window (+-%.1f m, the full turn; it widens after each search "
                  "that finds nothing, up to +-%.1f m: window/global_widest_half_xy_m) "
                  "included: the vehicle is probably farther from it than that",
                  r.window.half_x_m, options_.policy.window.global_widest_half_xy_m);
  } else if (lost_after > 0) {
    std::snprintf(searched, sizeof(searched),
                  "after %d rejections in a row (relocalization/lost_after_rejections) it "
                  "searches +-%.1f m and the full turn around it (window/global_max_half_xy_m), "
                  "a vehicle farther off is never matched",
                  lost_after, global_m);
  } else {
    std::snprintf(searched, sizeof(searched),
                  "it searches no wider (relocalization/lost_after_rejections is 0)");
  }
  std::string fix;
  if (source == PriorSource::kConfigured) {
    fix =
        ", or correct the matcher's initial_pose/x, initial_pose/y, initial_pose/yaw (launch "
        "arguments initial_x, initial_y, initial_yaw)";
  } else if (source == PriorSource::kPreviousMatch) {
    fix = " (the pose was the match remembered at this stamp after time went backwards)";
  }
  ROS_WARN(
      "%s: no match accepted in %d scans searched around the %s pose (x %.1f, y %.1f, yaw "
      "%.2f), up to +-%.1f m from it (last reason: %s); %s. Give a pose within a few metres of "
      "the vehicle on /initialpose (rviz '2D Pose Estimate')%s",
      name_.c_str(), acquisition_.rejections(), priorSourceName(source), p.x, p.y, p.yaw,
      acquisition_.widestWindowM(), r.reason.c_str(), searched, fix.c_str());
}

void Matcher::warnInputs(double now_s) {
  for (const InputSilence& silence : inputs_.due(now_s)) {
    ROS_WARN(
        "%s: no messages on %s %s: is the LIDAR driver or the bag (rosbag play --clock) "
        "running? The matcher reads the merged cloud from `velodyne_points`, remapped to the "
        "launch argument points_topic (merge_clouds:=true: the cloud merger's output)",
        name_.c_str(), silence.name.c_str(),
        silenceText(silence.ever_heard, silence.silent_for_s).c_str());
  }
  // Scans arrive, but there is nothing to search around.
  const bool waiting = last_mode_ == "no_prior" && !inputs_.silent(scans_input_, now_s) &&
                       inputs_.everHeard(scans_input_);
  if (!waiting) {
    no_prior_since_s_ = -1.0;
    no_prior_line_.reset();
    return;
  }
  if (no_prior_since_s_ < 0.0) no_prior_since_s_ = now_s;
  if (now_s - no_prior_since_s_ >= inputs_.silentAfter() && no_prior_line_.due(now_s)) {
    ROS_WARN(
        "%s: scans arrive but there is no pose to search around: give one on /initialpose (rviz "
        "'2D Pose Estimate'), or start from a configured pose with the matcher's "
        "initial_pose/enabled true and initial_pose/x, initial_pose/y, initial_pose/yaw "
        "(localization.launch use_initial_pose:=true initial_x:=... initial_y:=... "
        "initial_yaw:=...)",
        name_.c_str());
  }
}

void Matcher::setupDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  diagnostics_->add(scan_topic_ + " topic status", [this](StatusBuilder& s) {
    // The watchdog's verdict first: it names the fix; then diagnostic_updater's rate and stamp
    // checks.
    const double now_s = ros::WallTime::now().toSec();
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      s.add("topic", scan_topic_);
      s.add("messages received", inputs_.count(scans_input_));
      s.add("time since last message [s]", fixed(inputs_.silentFor(scans_input_, now_s), 2));
      if (inputs_.silent(scans_input_, now_s)) {
        s.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                  "no messages on " + scan_topic_ + " " +
                      silenceText(inputs_.everHeard(scans_input_),
                                  inputs_.silentFor(scans_input_, now_s)) +
                      " (launch argument points_topic)");
      }
      warnInputs(now_s);
    }
    scan_rate_.fill(s);
  });
  diagnostics_->add("scan matching", [this](StatusBuilder& s) {
    size_t chunks = 0;
    uint64_t version = 0;
    bool have_index = false;
    uint64_t ignored_indices = 0;
    std::string map_publisher;
    {
      std::lock_guard<std::mutex> lock(map_mutex_);
      chunks = map_client_.chunks().size();
      version = map_client_.mapVersion();
      have_index = map_client_.hasIndex();
      ignored_indices = map_client_.ignoredIndices() + map_client_.rejectedIndices();
      map_publisher = map_client_.publisher();
    }
    // Method fused: the second layer (matcher_reflectivity.cpp).
    const bool fused = options_.method.method == MatchMethod::kFused;
    bool layers_mismatch = false;
    const std::string reflectivity_problem =
        fused ? addReflectivityDiagnostics(s, &layers_mismatch) : "";
    uint64_t dropped_total = 0;
    {
      std::lock_guard<std::mutex> lock(session_mutex_);
      dropped_total = session_.droppedTotal();
    }
    std::lock_guard<std::mutex> lock(stats_mutex_);
    const double now_s = ros::WallTime::now().toSec();
    s.add("scan rate [Hz]", fixed(inputs_.rateHz(scans_input_, now_s), 2));
    s.add("match (accepted) rate [Hz]", fixed(inputs_.rateHz(matches_input_, now_s), 2));
    size_t ok = 0;
    for (bool a : recent_accepted_) ok += a ? 1 : 0;
    const double share =
        recent_accepted_.empty() ? 0.0 : static_cast<double>(ok) / recent_accepted_.size();
    s.add("accepted share (last 50)", fixed(share, 2));
    s.add("scans processed", scans_);
    s.add("matches accepted", accepted_);
    s.add("last log-likelihood per point [nats]", fixed(last_ll_per_point_, 3));
    size_t certified_recent = 0;
    for (bool c : recent_certified_) certified_recent += c ? 1 : 0;
    const double certified_share =
        recent_certified_.empty()
            ? 0.0
            : static_cast<double>(certified_recent) / recent_certified_.size();
    s.add("certified share of accepted (last 50)", fixed(certified_share, 2));
    s.add("matches certified", certified_);
    s.add("last certificate", last_certificate_);
    s.add("last protection level x-y [m]", fixed(last_protection_xy_m_, 2));
    s.add("last separation [nats per point]", fixed(last_separation_, 3));
    s.add("last search time [ms]", fixed(last_search_ms_, 1));
    s.add("last total time [ms]", fixed(last_total_ms_, 1));
    s.add("window half x, y [m], heading [deg]",
          fixed(last_window_.half_x_m, 2) + ", " + fixed(last_window_.half_y_m, 2) + ", " +
              fixed(last_window_.half_heading_rad * 180.0 / M_PI, 1));
    s.add("chunks held", chunks);
    s.add("map version", version);
    s.add("map server followed", map_publisher);
    s.add("map indices ignored (other publishers, invalid)", ignored_indices);
    s.add("dropped scans (total)", dropped_total);
    s.add("malformed or empty clouds", bad_clouds_);
    s.add("time went backwards (resets)", time_resets_);
    s.add("time went backwards (recovered from the match history)", time_recalls_);
    s.add("scan processing failures (answered)", processing_failures_);
    s.add("prior mode", last_mode_);
    s.add("prior source", last_prior_source_);
    s.add("last reason", last_reason_);
    s.add("rejected scans around the explicit pose", acquisition_.rejections());
    if (!have_index || chunks == 0) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no map (no chunks received)");
    } else if (last_mode_ == "no_prior") {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                "no prior: waiting for an initial pose (/initialpose or initial_pose/*)");
    } else if (acquisition_.stuck()) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                "no match in " + std::to_string(acquisition_.rejections()) + " scans around the " +
                    acquisition_source_ +
                    " pose: give a pose near the vehicle on /initialpose (or correct "
                    "initial_pose/x, y, yaw): " +
                    last_reason_);
    } else if (recent_accepted_.size() >= 5 && share < options_.min_accepted_share) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "few matches accepted: " + last_reason_);
    } else if (recent_certified_.size() >= 5 && certified_share < options_.min_accepted_share) {
      s.summary(
          diagnostic_msgs::DiagnosticStatus::WARN,
          "few matches certified (ambiguous surroundings or a wrong prior): " + last_certificate_);
    }
    if (!reflectivity_problem.empty()) {
      // The layers cannot be searched together: nothing is matched until the maps are fixed.
      s.summary(layers_mismatch ? diagnostic_msgs::DiagnosticStatus::ERROR
                                : diagnostic_msgs::DiagnosticStatus::WARN,
                "method fused: " + reflectivity_problem);
    }
  });
}

}  // namespace node
}  // namespace gmm_localization
