#include "gmm_localization/core/localization/acquisition_watch.h"

#include <algorithm>

namespace gmm_localization {

int acquisitionWarnAfter(const RelocalizationPolicyOptions& r) {
  return std::max(1, r.max_consecutive_rejections);
}

void AcquisitionWatch::onScan(uint64_t explicit_generation, MatchOutcome outcome,
                              double window_half_xy_m) {
  if (outcome == MatchOutcome::kSkipped) return;
  if (explicit_generation != generation_) {
    // Another pose (or none: tracking) from now on: its own count.
    generation_ = explicit_generation;
    rejections_ = 0;
    widest_m_ = 0.0;
    reported_ = false;
  }
  if (generation_ == 0) return;
  if (outcome == MatchOutcome::kAccepted) {
    rejections_ = 0;
    reported_ = false;
    return;
  }
  ++rejections_;
  widest_m_ = std::max(widest_m_, window_half_xy_m);
}

bool AcquisitionWatch::stuck() const {
  return generation_ != 0 && rejections_ >= options_.warn_after_rejections;
}

bool AcquisitionWatch::due(double now_s) {
  if (!stuck()) return false;
  if (reported_ && now_s - reported_s_ < options_.repeat_s && now_s >= reported_s_) return false;
  reported_ = true;
  reported_s_ = now_s;
  return true;
}

}  // namespace gmm_localization
