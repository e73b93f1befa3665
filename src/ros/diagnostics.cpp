#include "gmm_localization/ros/diagnostics.h"

#include <algorithm>

namespace gmm_localization {
namespace node {

void StatusBuilder::summary(uint8_t level, const std::string& message) {
  if (level > status_.level || status_.message.empty()) {
    status_.level = std::max<uint8_t>(static_cast<uint8_t>(status_.level), level);
    status_.message = message;
  }
}

void StatusBuilder::add(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  kv.value = value;
  status_.values.push_back(kv);
}

void FrequencyMonitor::tick(const ros::WallTime& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  events_.push_back(now);
  while (!events_.empty() && (now - events_.front()).toSec() > window_s_) events_.pop_front();
}

double FrequencyMonitor::rateHz(const ros::WallTime& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  while (!events_.empty() && (now - events_.front()).toSec() > window_s_) events_.pop_front();
  return static_cast<double>(events_.size()) / window_s_;
}

void FrequencyMonitor::fill(StatusBuilder& s, const std::string& what) {
  const double hz = rateHz();
  s.add(what + " rate [Hz]", hz);
  if (hz < min_hz_) {
    s.summary(diagnostic_msgs::DiagnosticStatus::WARN, what + " rate too low");
  } else if (hz > max_hz_) {
    s.summary(diagnostic_msgs::DiagnosticStatus::WARN, what + " rate too high");
  }
}

Diagnostics::Diagnostics(ros::NodeHandle& nh, const std::string& hardware_id, double period_s)
    : hardware_id_(hardware_id) {
  // Absolute topic: aggregators expect /diagnostics whatever the node's namespace.
  pub_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  timer_ = nh.createWallTimer(ros::WallDuration(period_s),
                              [this](const ros::WallTimerEvent&) { update(); });
}

void Diagnostics::add(const std::string& name, Task task) {
  std::lock_guard<std::mutex> lock(mutex_);
  tasks_.emplace_back(name, std::move(task));
}

void Diagnostics::update() {
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [name, task] : tasks_) {
    StatusBuilder s;
    s.status().level = diagnostic_msgs::DiagnosticStatus::OK;
    task(s);
    s.status().name = hardware_id_ + ": " + name;
    s.status().hardware_id = hardware_id_;
    if (s.status().message.empty()) s.status().message = "OK";
    array.status.push_back(s.status());
  }
  pub_.publish(array);
}

}  // namespace node
}  // namespace gmm_localization
