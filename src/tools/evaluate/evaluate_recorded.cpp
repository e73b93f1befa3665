#include "evaluate/evaluate_recorded.h"

#include <chrono>
#include <cmath>
#include <ostream>
#include <string>

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "evaluate/evaluate_bag.h"
#include "gmm_localization/MatchStatus.h"

namespace gmm_localization {
namespace eval {
namespace {

PoseStamped2 planarFromPose(const geometry_msgs::Pose& pose, double t) {
  const auto& q = pose.orientation;
  PoseStamped2 p;
  p.t = t;
  p.x = pose.position.x;
  p.y = pose.position.y;
  p.z = pose.position.z;
  p.yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  return p;
}

MatchRow rowOf(const MatchStatus& s, const Trajectory& truth) {
  MatchRow r;
  r.stamp_s = s.header.stamp.toSec();
  // The status does not say whether a search ran; one that scored nothing was skipped.
  r.outcome = s.accepted ? "accepted" : (s.search_evaluations == 0 ? "skipped" : "rejected");
  r.reason = s.reason;
  r.prior_source = s.prior_source;
  r.window_half_x_m = s.window_half_x_m;
  r.window_half_heading_rad = s.window_half_heading_rad;
  r.input_points = s.input_points;
  r.search_points = s.search_points;
  r.evaluations = s.search_evaluations;
  r.search_fraction = s.search_fraction;
  r.log_likelihood_per_point = s.log_likelihood_per_point;
  r.map_coverage = s.map_coverage;
  r.filter_ms = s.filter_ms;
  r.search_ms = s.search_ms;
  r.refine_ms = s.refine_ms;
  r.total_ms = s.total_ms;
  r.latency_s = s.latency_ms / 1000.0;
  r.dropped_before = s.dropped_scans;
  if (s.accepted) {
    const auto t = truth.at(r.stamp_s, kTruthGapS);
    if (t) {
      r.has_pose = true;
      r.pose = planarFromPose(s.pose.pose, r.stamp_s);
      r.error = vehicleFrameError(r.pose, *t);
      r.truth = *t;
    }
  }
  return r;
}

/// Messages of a topic that did not deserialize as the type this build expects.
struct ForeignMessages {
  size_t count = 0;
  std::string datatype, md5;  ///< of the first one

  void add(const rosbag::MessageInstance& m) {
    if (count++ == 0) {
      datatype = m.getDataType();
      md5 = m.getMD5Sum();
    }
  }
  /// Empty when there were none, else what they were against what this build reads.
  std::string describe(const std::string& topic, const std::string& want_type,
                       const std::string& want_md5) const {
    if (count == 0) return {};
    const std::string what = datatype == want_type
                                 ? "an older or newer definition of " + datatype + " (md5 " + md5 +
                                       "; this build reads md5 " + want_md5 + ")"
                                 : datatype + ", not " + want_type;
    return std::to_string(count) + " message(s) on " + topic + " are " + what;
  }
};

}  // namespace

Result<EvaluationResults> runRecordedEvaluation(const RecordedEvaluationConfig& c,
                                                std::ostream& log) {
  using R = Result<EvaluationResults>;
  const auto t0 = std::chrono::steady_clock::now();
  auto truth = readTrajectory(c.bag, c.topics.ground_truth);
  if (!truth) return R::failure(truth.error());
  rosbag::Bag bag;
  try {
    bag.open(c.bag, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    return R::failure("cannot open bag '" + c.bag + "': " + e.what());
  }
  EvaluationResults out;
  out.info.mode = "recorded";
  out.info.dataset = c.dataset;
  out.info.bag = c.bag;
  size_t statuses = 0, odometry = 0;
  // Messages on the two topics whose definition is not the one this build reads (a recording
  // from an older MatchStatus, or another type on the topic): counted, never silently skipped.
  ForeignMessages foreign_status, foreign_ekf;
  double next_ekf = -INFINITY;
  rosbag::View view(bag,
                    rosbag::TopicQuery(std::vector<std::string>{c.topics.ekf, c.topics.status}));
  for (const rosbag::MessageInstance& m : view) {
    if (m.getTopic() == c.topics.status) {
      const auto s = m.instantiate<MatchStatus>();
      if (!s) {
        foreign_status.add(m);
        continue;
      }
      ++statuses;
      out.matches.push_back(rowOf(*s, *truth));
      out.info.dropped_scans += s->dropped_scans;
    } else {
      const auto o = m.instantiate<nav_msgs::Odometry>();
      if (!o) {
        foreign_ekf.add(m);
        continue;
      }
      ++odometry;
      const double t = o->header.stamp.toSec();
      if (c.ekf_rate_hz > 0.0 && t < next_ekf) continue;
      const auto gt = truth->at(t, kTruthGapS);
      if (!gt) continue;
      // Next sample on the rate's time grid (messages come at the publisher's own rate).
      if (c.ekf_rate_hz > 0.0) next_ekf = (std::floor(t * c.ekf_rate_hz) + 1.0) / c.ekf_rate_hz;
      EkfRow row;
      row.t = t;
      row.estimate = planarFromPose(o->pose.pose, t);
      row.truth = *gt;
      row.error = vehicleFrameError(row.estimate, row.truth);
      row.sigma_x_m = std::sqrt(std::max(0.0, o->pose.covariance[0]));
      row.sigma_y_m = std::sqrt(std::max(0.0, o->pose.covariance[7]));
      row.sigma_yaw_rad = std::sqrt(std::max(0.0, o->pose.covariance[35]));
      out.ekf.push_back(row);
    }
  }
  const std::string status_foreign =
      foreign_status.describe(c.topics.status, ros::message_traits::DataType<MatchStatus>::value(),
                              ros::message_traits::MD5Sum<MatchStatus>::value());
  const std::string ekf_foreign =
      foreign_ekf.describe(c.topics.ekf, ros::message_traits::DataType<nav_msgs::Odometry>::value(),
                           ros::message_traits::MD5Sum<nav_msgs::Odometry>::value());
  if (statuses == 0 && !status_foreign.empty()) {
    return R::failure(status_foreign +
                      ": none could be read, so the matches cannot be scored. Replay the source "
                      "bag again with this build (replay.launch record:=...) and evaluate that "
                      "recording");
  }
  if (!status_foreign.empty()) out.info.notes.push_back(status_foreign + " (skipped)");
  if (!ekf_foreign.empty()) out.info.notes.push_back(ekf_foreign + " (skipped)");
  if (statuses == 0 && foreign_status.count == 0) {
    out.info.notes.push_back("no " + c.topics.status + " message: the matcher never ran");
  }
  if (odometry == 0 && foreign_ekf.count == 0) {
    out.info.notes.push_back("no " + c.topics.ekf + " message: the EKF never started");
  }
  // The drive's span: the ground truth the player published.
  out.info.duration_s = truth->endTime() - truth->startTime();
  if (!c.source_bag.empty()) {
    out.info.scans_in_bag = countMessages(c.source_bag, c.cloud_topic);
  }
  out.info.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  log << "recorded: " << statuses << " statuses, " << odometry << " EKF messages, " << truth->size()
      << " ground-truth poses over " << out.info.duration_s << " s" << std::endl;
  return out;
}

}  // namespace eval
}  // namespace gmm_localization
