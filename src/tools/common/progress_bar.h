#pragma once
// A one-line progress bar with ETA on stderr for command-line tools. On a terminal it redraws
// in place (at most 5 times a second); otherwise it prints a line every 10%.

#include <chrono>
#include <string>

namespace gmm_localization {
namespace tools {

class ProgressBar {
 public:
  ProgressBar(std::string label, bool enabled);
  /// fraction in [0, 1] (ignored when not finite); `detail` is shown after the bar.
  void update(double fraction, const std::string& detail);
  /// Draws 100% and ends the line.
  void finish(const std::string& detail);
  double elapsedSeconds() const;

 private:
  void draw(double fraction, const std::string& detail, bool final_line);

  std::string label_;
  bool enabled_;
  bool tty_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_decile_ = -1;
};

/// "1:05:03", "4:07", "12 s"
std::string formatDuration(double seconds);
/// 1234567 -> "1,234,567"
std::string withCommas(uint64_t value);

}  // namespace tools
}  // namespace gmm_localization
