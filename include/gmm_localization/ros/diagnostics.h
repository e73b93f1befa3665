#pragma once
// A small diagnostics publisher in the spirit of diagnostic_updater (not packaged in Debian):
// named tasks fill a DiagnosticStatus, published on /diagnostics at a fixed period; a frequency
// monitor and a stamp-age monitor cover the usual "rate and timestamp" checks.

#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>

namespace gmm_localization {
namespace node {

/// Builds one status: level, message and key-value pairs.
class StatusBuilder {
 public:
  /// Raises the level to `level` (never lowers it) and, when raised, sets the message.
  void summary(uint8_t level, const std::string& message);
  template <typename T>
  void add(const std::string& key, const T& value) {
    add(key, std::to_string(value));
  }
  void add(const std::string& key, const std::string& value);
  void add(const std::string& key, const char* value) { add(key, std::string(value)); }
  void add(const std::string& key, bool value) { add(key, std::string(value ? "true" : "false")); }
  diagnostic_msgs::DiagnosticStatus& status() { return status_; }

 private:
  diagnostic_msgs::DiagnosticStatus status_;
};

/// Counts events and reports their rate over a sliding window against [min_hz, max_hz].
class FrequencyMonitor {
 public:
  FrequencyMonitor(double min_hz, double max_hz, double window_s = 5.0)
      : min_hz_(min_hz), max_hz_(max_hz), window_s_(window_s) {}
  void tick(const ros::WallTime& now = ros::WallTime::now());
  void fill(StatusBuilder& s, const std::string& what);
  double rateHz(const ros::WallTime& now = ros::WallTime::now());

 private:
  std::mutex mutex_;
  std::deque<ros::WallTime> events_;
  double min_hz_, max_hz_, window_s_;
};

class Diagnostics {
 public:
  using Task = std::function<void(StatusBuilder&)>;
  /// hardware_id: e.g. the nodelet name. Publishes on /diagnostics every period_s.
  Diagnostics(ros::NodeHandle& nh, const std::string& hardware_id, double period_s = 1.0);
  void add(const std::string& name, Task task);
  /// Publishes now (also called by the timer).
  void update();

 private:
  ros::Publisher pub_;
  ros::WallTimer timer_;
  std::string hardware_id_;
  std::vector<std::pair<std::string, Task>> tasks_;
  std::mutex mutex_;
};

}  // namespace node
}  // namespace gmm_localization
