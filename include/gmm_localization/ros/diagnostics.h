#pragma once
// Diagnostics on /diagnostics through the standard diagnostic_updater (Debian:
// libdiagnostic-updater-dev): a diagnostic_updater::Updater per nodelet publishes the named
// tasks, and each input topic's rate and stamp age are checked by diagnostic_updater's
// FrequencyStatus and TimeStampStatus (the two halves of diagnostic_updater::TopicDiagnostic).
//
// Status names are "<nodelet name>: <task>", e.g. "/localization/matcher: scan matching" (the
// nodelet's name, not its manager's: all nodelets of a manager share one ROS node name), the
// hardware_id is the nodelet name. They are published every second of wall time, so that they
// keep coming while a bag's clock is paused. config/analyzers.yaml groups them for
// diagnostic_aggregator (launch/localization.launch diagnostics_aggregator:=true).

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <ros/ros.h>

namespace gmm_localization {
namespace node {

/// Wall-clock seconds: diagnostics age problems in wall time, so they keep ageing while a bag's
/// clock is paused.
inline double wallNow() { return ros::WallTime::now().toSec(); }
/// A problem this recent (wall seconds) keeps its WARN in a nodelet's status.
constexpr double kRecentProblemS = 10.0;

/// A nodelet's latest problem: kept for its diagnostic (a WARN while recent()) and logged as a
/// ROS_WARN naming the nodelet at most every 5 s of wall time. Not thread-safe: the nodelet's
/// mutex guards it.
class ProblemLog {
 public:
  explicit ProblemLog(std::string nodelet_name) : name_(std::move(nodelet_name)) {}
  void report(const std::string& what);
  const std::string& last() const { return last_; }
  /// A problem was reported within kRecentProblemS (wall).
  bool recent() const { return wallNow() - time_s_ < kRecentProblemS; }

 private:
  std::string name_, last_;
  double time_s_ = -1e9;  ///< wall time of last_ [s]
  double log_s_ = -1e9;   ///< wall time of the last warning logged [s]
};

/// A number with `digits` decimals, for a status's values.
inline std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

/// Fills one status: level, message and key-value pairs.
class StatusBuilder {
 public:
  explicit StatusBuilder(diagnostic_updater::DiagnosticStatusWrapper& status) : status_(status) {}
  /// Raises the level to `level` (never lowers it) and, when raised, sets the message: the first
  /// problem found names the status.
  void summary(uint8_t level, const std::string& message);
  /// Merges a check's verdict as diagnostic_updater's composite tasks do (mergeSummary): the
  /// worse level; the messages of problems joined with "; ".
  void merge(uint8_t level, const std::string& message);
  template <typename T>
  void add(const std::string& key, const T& value) {
    add(key, std::to_string(value));
  }
  void add(const std::string& key, const std::string& value);
  void add(const std::string& key, const char* value) { add(key, std::string(value)); }
  void add(const std::string& key, bool value) { add(key, std::string(value ? "true" : "false")); }
  diagnostic_msgs::DiagnosticStatus& status() { return status_; }

 private:
  diagnostic_updater::DiagnosticStatusWrapper& status_;
};

/// Rate and stamp-age checks of one topic: diagnostic_updater::FrequencyStatus (messages per
/// second over the last 5 updates against [min_hz, max_hz] with 10 % tolerance; ERROR "No events
/// recorded." when none came) and, once stamps are given, TimeStampStatus (ERROR when a stamp
/// lies more than max_delay_s behind the ROS clock or min_delay_s ahead of it; a bag played
/// without --clock, or use_sim_time forgotten, shows here). Thread-safe.
class FrequencyMonitor {
 public:
  FrequencyMonitor(double min_hz, double max_hz, double max_delay_s = 5.0,
                   double min_delay_s = -1.0);
  /// One message (rate).
  void tick() { frequency_->tick(); }
  /// The stamp of one message (its age against ros::Time::now()); counted in the rate by tick().
  void stamp(const ros::Time& stamp);
  /// Runs both checks into s (their keys, their verdict merged). Each run ends the checks'
  /// window: call it from one status only, once per update.
  void fill(StatusBuilder& s);

 private:
  double min_hz_, max_hz_;  ///< FrequencyStatusParam points at these
  std::unique_ptr<diagnostic_updater::FrequencyStatus> frequency_;
  std::unique_ptr<diagnostic_updater::TimeStampStatus> stamps_;
  std::atomic<bool> stamped_{false};
};

/// "for 6.2 s" (an input heard before), or "in the 5.0 s since start-up" (never heard).
std::string silenceText(bool ever_heard, double silent_for_s);

class Diagnostics {
 public:
  using Task = std::function<void(StatusBuilder&)>;
  /// hardware_id: the nodelet's name, which also prefixes the status names. pnh: the nodelet's
  /// private handle (diagnostic_updater reads ~diagnostic_period there; the statuses are
  /// published every period_s of wall time here).
  Diagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& pnh, const std::string& hardware_id,
              double period_s = 1.0);
  /// A status named "<hardware_id>: <name>"; the task starts from OK with no message ("OK" when
  /// it sets none).
  void add(const std::string& name, Task task);
  /// Publishes now (also called by the timer).
  void update();

 private:
  // Declared before the timer, destroyed after it: no update runs on a dead updater.
  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
};

}  // namespace node
}  // namespace gmm_localization
