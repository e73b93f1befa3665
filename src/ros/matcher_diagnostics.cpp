// Matcher health on /diagnostics (matcher.h): scan and match rates, accepted share, last score
// per point, certified share and last certificate, search time, window, chunks held, dropped scans,
// prior mode and last reason.
#include <cmath>
#include <cstdio>

#include "gmm_localization/ros/matcher.h"

namespace gmm_localization {
namespace node {
namespace {

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

void Matcher::record(const MatchReport& r, uint32_t dropped) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++scans_;
  if (r.accepted()) {
    ++accepted_;
    match_rate_.tick();
  }
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

void Matcher::setupDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, name_);
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
      ignored_indices = map_client_.ignoredIndices();
      map_publisher = map_client_.publisher();
    }
    uint64_t dropped_total = 0;
    {
      std::lock_guard<std::mutex> lock(session_mutex_);
      dropped_total = session_.droppedTotal();
    }
    std::lock_guard<std::mutex> lock(stats_mutex_);
    scan_rate_.fill(s, "scan");
    s.add("match (accepted) rate [Hz]", fixed(match_rate_.rateHz(), 2));
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
    if (!have_index || chunks == 0) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no map (no chunks received)");
    } else if (last_mode_ == "no_prior") {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no prior: waiting for an initial pose");
    } else if (recent_accepted_.size() >= 5 && share < options_.min_accepted_share) {
      s.summary(diagnostic_msgs::DiagnosticStatus::WARN, "few matches accepted: " + last_reason_);
    } else if (recent_certified_.size() >= 5 && certified_share < options_.min_accepted_share) {
      s.summary(
          diagnostic_msgs::DiagnosticStatus::WARN,
          "few matches certified (ambiguous surroundings or a wrong prior): " + last_certificate_);
    }
  });
}

}  // namespace node
}  // namespace gmm_localization
