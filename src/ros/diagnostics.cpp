#include "gmm_localization/ros/diagnostics.h"

#include <algorithm>
#include <cstdio>

namespace gmm_localization {
namespace node {

void StatusBuilder::summary(uint8_t level, const std::string& message) {
  if (level > status_.level || status_.message.empty()) {
    status_.level = std::max<uint8_t>(static_cast<uint8_t>(status_.level), level);
    status_.message = message;
  }
}

void StatusBuilder::merge(uint8_t level, const std::string& message) {
  status_.mergeSummary(level, message);
}

void StatusBuilder::add(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  kv.value = value;
  status_.values.push_back(kv);
}

FrequencyMonitor::FrequencyMonitor(double min_hz, double max_hz, double max_delay_s,
                                   double min_delay_s)
    : min_hz_(min_hz), max_hz_(max_hz) {
  frequency_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&min_hz_, &max_hz_, 0.1, 5));
  stamps_ = std::make_unique<diagnostic_updater::TimeStampStatus>(
      diagnostic_updater::TimeStampStatusParam(min_delay_s, max_delay_s));
}

void FrequencyMonitor::stamp(const ros::Time& stamp) {
  stamps_->tick(stamp);
  stamped_ = true;
}

void FrequencyMonitor::fill(StatusBuilder& s) {
  auto run = [&s](diagnostic_updater::DiagnosticTask& check) {
    diagnostic_updater::DiagnosticStatusWrapper result;
    result.level = diagnostic_msgs::DiagnosticStatus::OK;
    check.run(result);
    s.merge(result.level, result.message);
    for (const diagnostic_msgs::KeyValue& kv : result.values) s.add(kv.key, kv.value);
  };
  run(*frequency_);
  // A topic whose stamps are not checked has no "No data since last update." either.
  if (stamped_) run(*stamps_);
}

void ProblemLog::report(const std::string& what) {
  last_ = what;
  const double now = wallNow();
  time_s_ = now;
  if (now - log_s_ < 5.0) return;
  log_s_ = now;
  ROS_WARN("%s: %s", name_.c_str(), what.c_str());
}

std::string silenceText(bool ever_heard, double silent_for_s) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), ever_heard ? "for %.1f s" : "in the %.1f s since start-up",
                silent_for_s);
  return buf;
}

Diagnostics::Diagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& pnh,
                         const std::string& hardware_id, double period_s)
    // Updater names each status "<node_name minus its first character>: <task>": "/" + the
    // nodelet's name keeps the leading slash ("/localization/matcher: scan matching").
    : updater_(nh, pnh, "/" + hardware_id) {
  updater_.setHardwareID(hardware_id);
  timer_ = nh.createWallTimer(ros::WallDuration(period_s),
                              [this](const ros::WallTimerEvent&) { update(); });
}

void Diagnostics::add(const std::string& name, Task task) {
  updater_.add(name, [task = std::move(task)](diagnostic_updater::DiagnosticStatusWrapper& w) {
    w.level = diagnostic_msgs::DiagnosticStatus::OK;
    w.message.clear();
    StatusBuilder s(w);
    task(s);
    if (w.message.empty()) w.message = "OK";
  });
}

void Diagnostics::update() { updater_.force_update(); }

}  // namespace node
}  // namespace gmm_localization
