#pragma once
// Shared by the vehicle rostests (vehicle_*.test, which run launch/localization.launch and
// launch/replay.launch on the fixture of scripts/make_test_fixture.sh): a recorder of what the
// stack publishes in /localization (checking every number is finite), the diagnostics and the
// log lines, ground truth interpolation and waiting helpers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <tf2_msgs/TFMessage.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace vehicle_test {

inline double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

inline Pose6 toPose(const geometry_msgs::Pose& p) { return fromIsometry(fromMsg(p)); }

template <size_t N>
bool allFinite(const boost::array<double, N>& a) {
  return std::all_of(a.begin(), a.end(), [](double v) { return std::isfinite(v); });
}

inline bool allFinite(const geometry_msgs::Pose& p) {
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) &&
         std::isfinite(p.position.z) && std::isfinite(p.orientation.x) &&
         std::isfinite(p.orientation.y) && std::isfinite(p.orientation.z) &&
         std::isfinite(p.orientation.w);
}

/// Polls `done` every 10 ms (wall) until it holds or timeout_s passed; returns its last value.
inline bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

/// Ground truth poses by stamp, linearly interpolated (yaw along the short arc).
class Truth {
 public:
  void add(double t, const Pose6& p) {
    if (!samples_.empty() && t <= samples_.back().first) return;
    samples_.emplace_back(t, p);
  }
  std::optional<Pose6> at(double t) const {
    auto it = std::lower_bound(samples_.begin(), samples_.end(), t,
                               [](const auto& s, double v) { return s.first < v; });
    if (it == samples_.end() || it == samples_.begin()) {
      if (it != samples_.end() && it->first == t) return it->second;
      return std::nullopt;
    }
    const auto& [t1, p1] = *it;
    const auto& [t0, p0] = *(it - 1);
    const double a = (t - t0) / (t1 - t0);
    Pose6 p = p0;
    p.x += a * (p1.x - p0.x);
    p.y += a * (p1.y - p0.y);
    p.z += a * (p1.z - p0.z);
    p.yaw += a * angleDiff(p1.yaw, p0.yaw);
    return p;
  }
  bool empty() const { return samples_.empty(); }
  double first() const { return samples_.front().first; }
  double last() const { return samples_.back().first; }

 private:
  std::vector<std::pair<double, Pose6>> samples_;
};

/// Horizontal and heading error of `estimate` against the truth at `t` [m, rad].
struct PoseError {
  double xy_m = NAN, yaw_rad = NAN;
  bool valid() const { return std::isfinite(xy_m); }
};
inline PoseError poseError(const Truth& truth, double t, const Pose6& estimate) {
  PoseError e;
  const auto g = truth.at(t);
  if (!g) return e;
  e.xy_m = std::hypot(estimate.x - g->x, estimate.y - g->y);
  e.yaw_rad = std::abs(angleDiff(estimate.yaw, g->yaw));
  return e;
}

/// One diagnostic status as seen at a wall time.
struct SeenDiagnostic {
  double wall_s;
  diagnostic_msgs::DiagnosticStatus status;
};

/// Records the stack's outputs (topics of docs/ros.md) with their wall arrival times.
class Outputs {
 public:
  /// subscribe_truth: also record /ground_truth/odom (when rosbag play publishes it).
  Outputs(ros::NodeHandle& nh, bool subscribe_truth) {
    subs_.push_back(nh.subscribe("/localization/status", 1000, &Outputs::onStatus, this));
    subs_.push_back(nh.subscribe("/localization/pose", 1000, &Outputs::onPose, this));
    subs_.push_back(nh.subscribe("/localization/odometry", 5000, &Outputs::onOdometry, this));
    subs_.push_back(nh.subscribe("/diagnostics", 500, &Outputs::onDiagnostics, this));
    // Every node publishes its log lines on /rosout (rosout aggregates them on /rosout_agg).
    subs_.push_back(nh.subscribe("/rosout", 2000, &Outputs::onLog, this));
    subs_.push_back(nh.subscribe("/tf", 5000, &Outputs::onTf, this));
    if (subscribe_truth) {
      subs_.push_back(nh.subscribe("/ground_truth/odom", 5000, &Outputs::onTruth, this));
    }
  }
  /// The subscriptions end first: shutdown() waits for a callback in progress, so none runs
  /// on a member already destroyed (the spinner threads outlive the test case).
  ~Outputs() {
    for (ros::Subscriber& s : subs_) s.shutdown();
  }
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;

  template <typename F>
  auto locked(F f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f();
  }

  /// The value of `key` in the latest status named `name` ("" when not seen).
  std::string diagnosticValue(const std::string& name, const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = diagnostics_.find(name);
    if (it == diagnostics_.end()) return "";
    for (const auto& kv : it->second.values) {
      if (kv.key == key) return kv.value;
    }
    return "";
  }
  /// Whether a status named `name` satisfying `pred` arrived after wall time `since_s`.
  bool sawDiagnostic(const std::string& name,
                     const std::function<bool(const diagnostic_msgs::DiagnosticStatus&)>& pred,
                     double since_s) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const SeenDiagnostic& d : diagnostic_history_) {
      if (d.wall_s >= since_s && d.status.name == name && pred(d.status)) return true;
    }
    return false;
  }
  /// Whether a log line of level >= `level` containing `text` arrived after wall time `since_s`.
  bool sawLog(uint8_t level, const std::string& text, double since_s) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [wall, log] : logs_) {
      if (wall >= since_s && log.level >= level && log.msg.find(text) != std::string::npos) {
        return true;
      }
    }
    return false;
  }
  /// Every diagnostic name seen.
  /// The map server has rasterized every chunk it wants, in a status that arrived after
  /// `since_s` (wall time); waits up to timeout_s.
  bool mapReadySince(double since_s, double timeout_s) {
    return waitFor(
        [&] {
          return sawDiagnostic(
              "/localization/map_server: chunks",
              [](const diagnostic_msgs::DiagnosticStatus& s) {
                std::string held, pending;
                for (const auto& kv : s.values) {
                  if (kv.key == "chunks held") held = kv.value;
                  if (kv.key == "chunks pending") pending = kv.value;
                }
                return pending == "0" && !held.empty() && held != "0";
              },
              since_s);
        },
        timeout_s);
  }

  std::vector<std::string> diagnosticNames() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> names;
    for (const auto& kv : diagnostics_) names.push_back(kv.first);
    return names;
  }

  std::vector<MatchStatus> statuses_;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses_;
  std::vector<nav_msgs::Odometry> odometry_;
  Truth truth_;
  bool non_finite_ = false;
  std::string non_finite_what_;

 private:
  static double wallNow() { return ros::WallTime::now().toSec(); }
  void flag(const std::string& what) {
    if (!non_finite_) non_finite_what_ = what;
    non_finite_ = true;
  }
  void onStatus(const MatchStatus::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.push_back(*m);
    if (!allFinite(m->pose.pose) || !allFinite(m->pose.covariance) || !std::isfinite(m->total_ms) ||
        !std::isfinite(m->latency_ms) || !std::isfinite(m->log_likelihood_per_point)) {
      flag("status at " + std::to_string(m->header.stamp.toSec()));
    }
  }
  void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_.push_back(*m);
    if (!allFinite(m->pose.pose) || !allFinite(m->pose.covariance)) {
      flag("pose at " + std::to_string(m->header.stamp.toSec()));
    }
  }
  void onOdometry(const nav_msgs::Odometry::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    odometry_.push_back(*m);
    const auto& v = m->twist.twist;
    if (!allFinite(m->pose.pose) || !allFinite(m->pose.covariance) ||
        !allFinite(m->twist.covariance) || !std::isfinite(v.linear.x) ||
        !std::isfinite(v.linear.y) || !std::isfinite(v.angular.z)) {
      flag("odometry at " + std::to_string(m->header.stamp.toSec()));
    }
  }
  void onTf(const tf2_msgs::TFMessage::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& t : m->transforms) {
      const auto& tr = t.transform;
      if (!std::isfinite(tr.translation.x) || !std::isfinite(tr.translation.y) ||
          !std::isfinite(tr.translation.z) || !std::isfinite(tr.rotation.w) ||
          !std::isfinite(tr.rotation.z)) {
        flag("TF " + t.header.frame_id + " -> " + t.child_frame_id);
      }
    }
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : m->status) {
      diagnostics_[s.name] = s;
      diagnostic_history_.push_back({wallNow(), s});
    }
  }
  void onLog(const rosgraph_msgs::Log::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    logs_.emplace_back(wallNow(), *m);
  }
  void onTruth(const nav_msgs::Odometry::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    truth_.add(m->header.stamp.toSec(), toPose(m->pose.pose));
  }

  std::vector<ros::Subscriber> subs_;
  std::mutex mutex_;
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> diagnostics_;
  std::vector<SeenDiagnostic> diagnostic_history_;
  std::vector<std::pair<double, rosgraph_msgs::Log>> logs_;
};

/// topic -> nodes publishing it, and topic -> nodes subscribing to it (master graph).
struct Graph {
  std::map<std::string, std::set<std::string>> publishers, subscribers;
};

inline bool readGraph(Graph* g) {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", request, response, payload, true)) return false;
  for (int kind = 0; kind < 2; ++kind) {
    auto& out = kind == 0 ? g->publishers : g->subscribers;
    for (int i = 0; i < payload[kind].size(); ++i) {
      const std::string topic = payload[kind][i][0];
      for (int j = 0; j < payload[kind][i][1].size(); ++j) {
        out[topic].insert(static_cast<std::string>(payload[kind][i][1][j]));
      }
    }
  }
  return true;
}

/// The error of the last EKF estimate the truth covers (the clock ends with the bag's last IMU
/// sample, a few ms after its last ground truth); invalid when there is none.
inline PoseError lastEkfError(Outputs& outputs, const Truth& truth) {
  PoseError e;
  outputs.locked([&] {
    for (auto it = outputs.odometry_.rbegin(); it != outputs.odometry_.rend() && !e.valid(); ++it) {
      e = poseError(truth, it->header.stamp.toSec(), toPose(it->pose.pose));
    }
    return 0;
  });
  return e;
}

/// What the vehicle tests call localized: within 0.3 m and 1 deg of the truth (the paper's
/// lane-keeping scale; the matches themselves are a few cm off on the fixture drive).
constexpr double kTolXyM = 0.3, kTolYawRad = 1.0 * M_PI / 180.0;

/// The drive ended localized: the last EKF estimate within tol_xy_m and tol_yaw_rad (printed
/// with `test`'s name).
inline void expectEndsLocalized(Outputs& outputs, const Truth& truth, const char* test,
                                double tol_xy_m, double tol_yaw_rad) {
  const PoseError e = lastEkfError(outputs, truth);
  ASSERT_TRUE(e.valid()) << "no EKF odometry within the ground truth's time span";
  std::printf("[%s] final EKF error %.3f m, %.3f deg\n", test, e.xy_m, e.yaw_rad * 180.0 / M_PI);
  EXPECT_LE(e.xy_m, tol_xy_m);
  EXPECT_LE(e.yaw_rad, tol_yaw_rad);
}

/// What the stack published over a played drive, and the truth.
struct DriveRecord {
  std::vector<MatchStatus> statuses;
  std::vector<nav_msgs::Odometry> odometry;
  Truth truth;
};

/// Waits (wall, up to timeout_s) until the ground truth played reaches end_stamp, then 3 s for
/// the last scans' statuses, and copies what was published; false when the bag never ended.
inline bool recordDrive(Outputs& outputs, double end_stamp, double timeout_s, DriveRecord* out) {
  const bool ended = waitFor(
      [&] {
        return outputs.locked(
            [&] { return !outputs.truth_.empty() && outputs.truth_.last() >= end_stamp - 0.02; });
      },
      timeout_s);
  if (!ended) return false;
  ros::WallDuration(3.0).sleep();
  outputs.locked([&] {
    out->statuses = outputs.statuses_;
    out->odometry = outputs.odometry_;
    out->truth = outputs.truth_;
    return 0;
  });
  return true;
}

/// The accepted matches of a drive: how many, the first and last, the worst error [m].
struct AcceptedMatches {
  size_t count = 0;
  const MatchStatus* first = nullptr;
  const MatchStatus* last = nullptr;
  double worst_m = 0.0;
};

/// Every accepted match within tol_xy_m of the truth (a failure names each one that is not).
inline AcceptedMatches expectAcceptedWithin(const std::vector<MatchStatus>& statuses,
                                            const Truth& truth, double tol_xy_m) {
  AcceptedMatches a;
  for (const MatchStatus& s : statuses) {
    if (!s.accepted) continue;
    ++a.count;
    if (a.first == nullptr) a.first = &s;
    a.last = &s;
    const PoseError e = poseError(truth, s.header.stamp.toSec(), toPose(s.pose.pose));
    if (!e.valid()) continue;
    a.worst_m = std::max(a.worst_m, e.xy_m);
    EXPECT_LE(e.xy_m, tol_xy_m) << "a match " << e.xy_m << " m off was accepted (prior "
                                << s.prior_source << ", window " << s.window_half_x_m << " m)";
  }
  return a;
}

/// No EKF estimate farther from the truth than max(tol_xy_m, 3 sigma of its x-y covariance);
/// returns the worst error / bound.
inline double expectEkfWithinItsSigma(const std::vector<nav_msgs::Odometry>& odometry,
                                      const Truth& truth, double tol_xy_m) {
  double worst_ratio = 0.0;
  for (const nav_msgs::Odometry& o : odometry) {
    const PoseError e = poseError(truth, o.header.stamp.toSec(), toPose(o.pose.pose));
    if (!e.valid()) continue;
    const double sigma = std::sqrt(o.pose.covariance[0] + o.pose.covariance[7]);
    const double bound = std::max(tol_xy_m, 3.0 * sigma);
    worst_ratio = std::max(worst_ratio, e.xy_m / bound);
    EXPECT_LE(e.xy_m, bound) << "EKF estimate " << e.xy_m << " m off with sigma " << sigma
                             << " m at " << o.header.stamp.toSec();
  }
  return worst_ratio;
}

/// Nothing non-finite was published, and the EKF published at all.
inline void expectNothingNonFinite(Outputs& outputs) {
  outputs.locked([&] {
    EXPECT_FALSE(outputs.non_finite_) << outputs.non_finite_what_;
    EXPECT_FALSE(outputs.odometry_.empty());
    return 0;
  });
}

}  // namespace vehicle_test
}  // namespace node
}  // namespace gmm_localization
