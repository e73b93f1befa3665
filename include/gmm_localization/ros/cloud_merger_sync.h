#pragma once
// The cloud merger's time-synchronisation policy, as a pure state machine (no ROS, no clock:
// stamps and arrival times are passed in).
//
// Policy (config/cloud_merger.yaml repeats it). The sensors spin unsynchronised at the same
// rate (HDL-32E: 10 Hz, phases anywhere in [0, T)), so any window of one period holds one
// revolution of each; a merged scan is such a set:
//  - A cycle opens with the first cloud accepted after the last output. A cloud joins the open
//    cycle while the cycle's stamps stay within max_stamp_spread_s (max - min < spread) and its
//    sensor is not in the cycle yet.
//  - The cycle is published (closed) when every sensor has delivered one cloud (complete); when
//    max_wait_s of arrival time have passed since its first cloud arrived (timeout: published
//    with the sensors present; the others are reported missing); or when a cloud arrives that
//    belongs to the next cycle (its stamp beyond the spread, or a second cloud of a sensor
//    already in the cycle): the open cycle is published as it is and the cloud opens the next.
//  - The merged scan's stamp is the earliest input stamp; per-point times are re-based to it.
//  - Clouds stamped before the last output's stamp are late: dropped and counted. A cloud
//    older than the open cycle's window, or an older second cloud of a sensor, is dropped and
//    counted as out of window.
//  - Time going backwards by more than backwards_reset_s (a looping bag, a restarted driver)
//    resets the state (the open cycle is discarded) and the cloud starts afresh.
// Why max_wait defaults to a little more than a period (0.12 s at 10 Hz) rather than a fraction
// of it: with phases spread over [0, T), the last revolution of a set ends up to T after the
// first, so a shorter wait would publish most scans without the last sensor.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gmm_localization/ros/cloud_conversion.h"

namespace gmm_localization {
namespace node {

struct MergeSyncOptions {
  size_t sensors = 4;               ///< number of input clouds per cycle, >= 1
  double max_wait_s = 0.12;         ///< arrival time a cycle waits for missing sensors [s]
  double max_stamp_spread_s = 0.1;  ///< stamps of one cycle span less than this [s]
  double backwards_reset_s = 1.0;   ///< a stamp this far before the last output resets [s]

  std::string validate() const;
};

/// One sensor's cloud, already moved into the output frame.
struct MergeInput {
  size_t sensor = 0;
  int64_t stamp_ns = 0;    ///< header.stamp [ns]
  double arrival_s = 0.0;  ///< receipt time on a monotonic clock [s]
  std::shared_ptr<const CloudData> cloud;
};

struct MergeCycle {
  enum class Closed { kComplete, kTimeout, kNextCycle, kRepeatedSensor };
  int64_t stamp_ns = 0;            ///< earliest input stamp [ns]
  std::vector<MergeInput> inputs;  ///< ordered by sensor index
  std::vector<size_t> missing;     ///< sensors without a cloud in this cycle, ascending
  double first_arrival_s = 0.0;    ///< arrival of the cycle's first cloud [s]
  Closed closed = Closed::kComplete;
};

enum class MergeVerdict { kAccepted, kLate, kOutOfWindow, kUnknownSensor };

struct MergeSyncCounters {
  uint64_t accepted = 0;
  uint64_t late = 0;
  uint64_t out_of_window = 0;
  uint64_t resets = 0;
  uint64_t complete = 0;    ///< cycles published with every sensor
  uint64_t incomplete = 0;  ///< cycles published with sensors missing
};

class MergeSynchronizer {
 public:
  explicit MergeSynchronizer(const MergeSyncOptions& options) : options_(options) {}

  /// Offers one cloud. Cycles it closes (0, 1 or 2: the open one and, with one sensor, its
  /// own) are appended to `closed`, oldest first.
  MergeVerdict add(MergeInput input, std::vector<MergeCycle>& closed);
  /// Closes the open cycle when max_wait_s has passed since its first cloud arrived.
  std::optional<MergeCycle> poll(double now_s);
  /// Forgets the open cycle and the last output (counted as a reset).
  void reset();

  bool cycleOpen() const { return !cycle_.empty(); }
  const MergeSyncCounters& counters() const { return counters_; }
  const MergeSyncOptions& options() const { return options_; }

 private:
  MergeCycle close(MergeCycle::Closed why);
  void open(MergeInput input, std::vector<MergeCycle>& closed);

  MergeSyncOptions options_;
  std::vector<MergeInput> cycle_;  // the open cycle, in arrival order
  int64_t lo_ns_ = 0, hi_ns_ = 0;  // stamp range of the open cycle
  double first_arrival_s_ = 0.0;
  bool has_output_ = false;
  int64_t last_output_ns_ = 0;
  MergeSyncCounters counters_;
};

}  // namespace node
}  // namespace gmm_localization
