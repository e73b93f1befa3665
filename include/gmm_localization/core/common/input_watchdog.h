#pragma once
// Inputs that should keep arriving (sensor topics): which one is silent, since when, how fast
// the others come, and when a silent one's console line is due. ROS-free: the caller passes the
// time (wall seconds, so that a paused bag clock still counts as silence) and locks.
//
//   InputWatchdog w(5.0, 30.0);        // silent after 5 s without a message; line every 30 s
//   const size_t imu = w.add("imu");
//   w.start(now);                       // messages are expected from now on
//   w.heard(imu, t);                    // at each message
//   for (const InputSilence& s : w.due(now)) log(s);  // when it falls silent, then every 30 s
//
// An input that was never heard counts as silent silent_after_s after start(); one that is heard
// again is re-armed (its next silence gets a line at once).

#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace gmm_localization {

struct InputSilence {
  size_t input = 0;
  std::string name;
  bool ever_heard = false;    ///< false: nothing since start()
  double silent_for_s = 0.0;  ///< since the last message, or since start() when never heard
};

class InputWatchdog {
 public:
  /// silent_after_s: an input without a message for this long is silent [s]; repeat_s: a silent
  /// input's line repeats this often [s]; rate_window_s: rates count the messages of this
  /// last span [s].
  explicit InputWatchdog(double silent_after_s = 5.0, double repeat_s = 30.0,
                         double rate_window_s = 5.0);

  /// Adds an input; returns its index (0, 1, ... in the order added). watch_silence false: only
  /// its rate and silence are kept, due() never names it (an event that may rightly stop).
  size_t add(const std::string& name, bool watch_silence = true);
  /// Messages are expected from now_s on (the silence of an input never heard counts from here).
  void start(double now_s);
  /// A message on `input` at now_s.
  void heard(size_t input, double now_s);

  bool everHeard(size_t input) const { return inputs_[input].ever_heard; }
  uint64_t count(size_t input) const { return inputs_[input].count; }
  /// Seconds since the input's last message, or since start() when never heard.
  double silentFor(size_t input, double now_s) const;
  bool silent(size_t input, double now_s) const;
  /// Messages per second over the last rate_window_s.
  double rateHz(size_t input, double now_s);
  double silentAfter() const { return silent_after_s_; }

  /// The silent inputs whose console line is due at now_s: when an input falls silent, then
  /// every repeat_s while it stays silent. Marks them as reported.
  std::vector<InputSilence> due(double now_s);

 private:
  struct Input {
    std::string name;
    bool watch_silence = true;
    bool ever_heard = false;
    double last_s = 0.0;
    uint64_t count = 0;
    std::deque<double> recent;  ///< message times within rate_window_s
    bool reported = false;      ///< the current silence has had its line
    double reported_s = 0.0;
  };
  void prune(Input& in, double now_s) const;

  double silent_after_s_, repeat_s_, rate_window_s_;
  double start_s_ = 0.0;
  std::vector<Input> inputs_;
};

/// One console line's throttle on a time the caller gives (wall seconds): due at once, then at
/// most every period_s. Unlike ROS_WARN_THROTTLE (one per call site, on the ROS clock, which
/// stands still while a bag is paused), one per instance and reset()-able.
class LineThrottle {
 public:
  explicit LineThrottle(double period_s) : period_s_(period_s) {}
  /// True when the line may be given now (and then counts it as given).
  bool due(double now_s) {
    if (given_ && now_s - last_s_ < period_s_ && now_s >= last_s_) return false;
    given_ = true;
    last_s_ = now_s;
    return true;
  }
  /// The condition ended: the next line is due at once.
  void reset() { given_ = false; }

 private:
  double period_s_;
  bool given_ = false;
  double last_s_ = 0.0;
};

}  // namespace gmm_localization
