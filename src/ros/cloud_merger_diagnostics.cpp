// Diagnostics of the cloud merger: one status per input, one for the output.
#include <diagnostic_msgs/DiagnosticStatus.h>

#include "gmm_localization/ros/cloud_merger.h"

namespace gmm_localization {
namespace node {
namespace {

using diagnostic_msgs::DiagnosticStatus;

}  // namespace

void CloudMerger::setUpDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  for (size_t i = 0; i < inputs_.size(); ++i) {
    diagnostics_->add("input " + inputs_[i]->topic, [this, i](StatusBuilder& s) {
      // The first WARN sets the message: specific problems before the rate check.
      Input& in = *inputs_[i];
      std::unique_lock<std::mutex> lock(mutex_);
      s.add("topic", nh_.resolveName(in.topic));
      s.add("frame", in.frame);
      s.add("clouds received", std::to_string(in.received));
      s.add("malformed clouds", std::to_string(in.malformed));
      s.add("clouds without TF", std::to_string(in.no_tf));
      s.add("late clouds dropped", std::to_string(in.late));
      s.add("out-of-window clouds dropped", std::to_string(in.out_of_window));
      s.add("non-finite points dropped", std::to_string(in.nonfinite_points));
      s.add("clouds merged without valid point times", std::to_string(in.untimed));
      if (!in.last_error.empty()) s.add("last problem", in.last_error);
      if (!in.last_time_problem.empty()) s.add("last point time problem", in.last_time_problem);
      const double now = ros::WallTime::now().toSec();
      if (in.received == 0) {
        s.summary(DiagnosticStatus::WARN, "no cloud received yet");
      } else if (now - in.last_error_time_s < kRecentProblemS) {
        s.summary(DiagnosticStatus::WARN, in.last_error);
      } else if (now - in.last_time_problem_s < kRecentProblemS) {
        s.summary(DiagnosticStatus::WARN, "merged scans not deskewed: " + in.last_time_problem);
      }
      lock.unlock();
      in.rate.fill(s);
    });
  }

  diagnostics_->add("output", [this](StatusBuilder& s) {
    std::unique_lock<std::mutex> lock(mutex_);
    const MergeSyncCounters& c = sync_.counters();
    s.add("scans published", std::to_string(published_));
    s.add("complete sets", std::to_string(c.complete));
    s.add("incomplete sets", std::to_string(c.incomplete));
    s.add("resets (time went backwards)", std::to_string(c.resets));
    s.add("scans with NaN point times", std::to_string(untimed_scans_));
    s.add("points in last scan", last_points_);
    s.add("last merge latency [ms]", last_latency_ms_);
    s.add("mean merge latency [ms]",
          published_ > 0 ? sum_latency_ms_ / static_cast<double>(published_) : 0.0);
    s.add("max merge latency [ms]", max_latency_ms_);
    if (ros::WallTime::now().toSec() - last_missing_time_s_ < kRecentProblemS) {
      std::string names;
      for (size_t i : last_missing_) names += (names.empty() ? "" : ", ") + inputs_[i]->topic;
      s.add("missing sensors", names);
      s.summary(DiagnosticStatus::WARN, "scans published without " + names);
    }
    lock.unlock();
    output_rate_.fill(s);
  });
}

}  // namespace node
}  // namespace gmm_localization
