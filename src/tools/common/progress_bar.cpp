#include "common/progress_bar.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace gmm_localization {
namespace tools {

std::string formatDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t < 60) {
    std::snprintf(buf, sizeof buf, "%ld s", t);
  } else if (t < 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  }
  return buf;
}

std::string withCommas(uint64_t v) {
  std::string s = std::to_string(v);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<size_t>(i), ",");
  return s;
}

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)),
      enabled_(enabled),
      tty_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

double ProgressBar::elapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressBar::update(double fraction, const std::string& detail) {
  if (!enabled_ || !std::isfinite(fraction)) return;
  fraction = std::min(std::max(fraction, 0.0), 1.0);
  const auto now = std::chrono::steady_clock::now();
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(200)) return;
    last_draw_ = now;
    draw(fraction, detail, false);
  } else {
    const int decile = static_cast<int>(fraction * 10.0);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    draw(fraction, detail, true);
  }
}

void ProgressBar::finish(const std::string& detail) {
  if (!enabled_) return;
  draw(1.0, detail, true);
}

void ProgressBar::draw(double fraction, const std::string& detail, bool final_line) {
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(kWidth, '.');
  const double elapsed = elapsedSeconds();
  // An ETA from the first item or the first second is noise (a first tile can be empty or
  // huge): show "ETA ..." until there is something to extrapolate from.
  std::string eta = "in " + formatDuration(elapsed);
  if (fraction < 1.0) {
    eta = fraction >= 0.02 && elapsed >= 1.0
              ? "ETA " + formatDuration(elapsed * (1.0 - fraction) / fraction)
              : "ETA ...";
  }
  std::fprintf(stderr, "%s%-8s [%s] %3d%%  %s  %s%s", tty_ ? "\r\033[K" : "", label_.c_str(),
               bar.c_str(), static_cast<int>(fraction * 100.0), eta.c_str(), detail.c_str(),
               final_line || !tty_ ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace tools
}  // namespace gmm_localization
