#include "gmm_localization/ros/cloud_merger_sync.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {
namespace node {
namespace {

int64_t toNs(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

}  // namespace

std::string MergeSyncOptions::validate() const {
  if (sensors < 1 || sensors > 64) {
    return "sensors=" + std::to_string(sensors) + " must be in [1, 64]";
  }
  if (!(max_wait_s > 0.0 && max_wait_s <= 10.0)) {
    return "max_wait_s=" + std::to_string(max_wait_s) + " must be in (0, 10]";
  }
  if (!(max_stamp_spread_s > 0.0 && max_stamp_spread_s <= 10.0)) {
    return "max_stamp_spread_s=" + std::to_string(max_stamp_spread_s) + " must be in (0, 10]";
  }
  if (!(backwards_reset_s >= max_stamp_spread_s && backwards_reset_s <= 3600.0)) {
    return "backwards_reset_s=" + std::to_string(backwards_reset_s) +
           " must be in [max_stamp_spread_s, 3600]";
  }
  return {};
}

MergeVerdict MergeSynchronizer::add(MergeInput in, std::vector<MergeCycle>& closed) {
  if (in.sensor >= options_.sensors) return MergeVerdict::kUnknownSensor;
  const int64_t s = in.stamp_ns;
  const int64_t backwards = toNs(options_.backwards_reset_s);
  // Time going backwards (bag loop): before the last output or the open cycle by far.
  if ((has_output_ && s < last_output_ns_ - backwards) || (cycleOpen() && s < lo_ns_ - backwards)) {
    reset();
  }
  if (has_output_ && s < last_output_ns_) {
    ++counters_.late;
    return MergeVerdict::kLate;
  }
  if (!cycleOpen()) {
    open(std::move(in), closed);
    return MergeVerdict::kAccepted;
  }
  const int64_t spread = toNs(options_.max_stamp_spread_s);
  const int64_t lo = std::min(lo_ns_, s), hi = std::max(hi_ns_, s);
  if (hi - lo >= spread) {
    if (s < lo_ns_) {  // older than the open cycle's window
      ++counters_.out_of_window;
      return MergeVerdict::kOutOfWindow;
    }
    closed.push_back(close(MergeCycle::Closed::kNextCycle));
    open(std::move(in), closed);
    return MergeVerdict::kAccepted;
  }
  const auto same = std::find_if(cycle_.begin(), cycle_.end(),
                                 [&](const MergeInput& c) { return c.sensor == in.sensor; });
  if (same != cycle_.end()) {
    if (s <= same->stamp_ns) {  // an older (or repeated) cloud of that sensor
      ++counters_.out_of_window;
      return MergeVerdict::kOutOfWindow;
    }
    closed.push_back(close(MergeCycle::Closed::kRepeatedSensor));
    open(std::move(in), closed);
    return MergeVerdict::kAccepted;
  }
  ++counters_.accepted;
  lo_ns_ = lo;
  hi_ns_ = hi;
  cycle_.push_back(std::move(in));
  if (cycle_.size() == options_.sensors) closed.push_back(close(MergeCycle::Closed::kComplete));
  return MergeVerdict::kAccepted;
}

void MergeSynchronizer::open(MergeInput in, std::vector<MergeCycle>& closed) {
  ++counters_.accepted;
  lo_ns_ = hi_ns_ = in.stamp_ns;
  first_arrival_s_ = in.arrival_s;
  cycle_.push_back(std::move(in));
  if (cycle_.size() == options_.sensors) closed.push_back(close(MergeCycle::Closed::kComplete));
}

std::optional<MergeCycle> MergeSynchronizer::poll(double now_s) {
  if (!cycleOpen() || now_s - first_arrival_s_ < options_.max_wait_s) return std::nullopt;
  return close(MergeCycle::Closed::kTimeout);
}

MergeCycle MergeSynchronizer::close(MergeCycle::Closed why) {
  MergeCycle c;
  c.stamp_ns = lo_ns_;
  c.first_arrival_s = first_arrival_s_;
  c.closed = why;
  c.inputs = std::move(cycle_);
  cycle_.clear();
  std::sort(c.inputs.begin(), c.inputs.end(),
            [](const MergeInput& a, const MergeInput& b) { return a.sensor < b.sensor; });
  size_t k = 0;
  for (size_t i = 0; i < options_.sensors; ++i) {
    if (k < c.inputs.size() && c.inputs[k].sensor == i) {
      ++k;
    } else {
      c.missing.push_back(i);
    }
  }
  ++(c.missing.empty() ? counters_.complete : counters_.incomplete);
  has_output_ = true;
  last_output_ns_ = c.stamp_ns;
  return c;
}

void MergeSynchronizer::reset() {
  cycle_.clear();
  has_output_ = false;
  last_output_ns_ = 0;
  ++counters_.resets;
}

}  // namespace node
}  // namespace gmm_localization
