#include "gmm_localization/core/common/input_watchdog.h"

namespace gmm_localization {

InputWatchdog::InputWatchdog(double silent_after_s, double repeat_s, double rate_window_s)
    : silent_after_s_(silent_after_s), repeat_s_(repeat_s), rate_window_s_(rate_window_s) {}

size_t InputWatchdog::add(const std::string& name, bool watch_silence) {
  Input in;
  in.name = name;
  in.watch_silence = watch_silence;
  inputs_.push_back(in);
  return inputs_.size() - 1;
}

void InputWatchdog::start(double now_s) { start_s_ = now_s; }

void InputWatchdog::heard(size_t input, double now_s) {
  Input& in = inputs_[input];
  in.ever_heard = true;
  in.last_s = now_s;
  ++in.count;
  in.recent.push_back(now_s);
  prune(in, now_s);
  in.reported = false;  // a later silence is a new one
}

double InputWatchdog::silentFor(size_t input, double now_s) const {
  const Input& in = inputs_[input];
  return now_s - (in.ever_heard ? in.last_s : start_s_);
}

bool InputWatchdog::silent(size_t input, double now_s) const {
  return silentFor(input, now_s) >= silent_after_s_;
}

void InputWatchdog::prune(Input& in, double now_s) const {
  // A message stamped after now_s (a clock that stepped back) is dropped with the old ones.
  while (!in.recent.empty() &&
         (now_s - in.recent.front() > rate_window_s_ || in.recent.front() > now_s)) {
    in.recent.pop_front();
  }
}

double InputWatchdog::rateHz(size_t input, double now_s) {
  Input& in = inputs_[input];
  prune(in, now_s);
  return rate_window_s_ > 0.0 ? static_cast<double>(in.recent.size()) / rate_window_s_ : 0.0;
}

std::vector<InputSilence> InputWatchdog::due(double now_s) {
  std::vector<InputSilence> out;
  for (size_t i = 0; i < inputs_.size(); ++i) {
    Input& in = inputs_[i];
    if (!in.watch_silence || !silent(i, now_s)) continue;
    if (in.reported && now_s - in.reported_s < repeat_s_ && now_s >= in.reported_s) continue;
    in.reported = true;
    in.reported_s = now_s;
    out.push_back(InputSilence{i, in.name, in.ever_heard, silentFor(i, now_s)});
  }
  return out;
}

}  // namespace gmm_localization
