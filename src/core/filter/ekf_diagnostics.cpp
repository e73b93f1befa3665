#include "gmm_localization/core/filter/ekf_diagnostics.h"

namespace gmm_localization {

const char* outcomeName(FuseOutcome outcome) {
  switch (outcome) {
    case FuseOutcome::kFused:
      return "fused";
    case FuseOutcome::kRejectedGate:
      return "rejected_gate";
    case FuseOutcome::kRejectedInvalid:
      return "rejected_invalid";
    case FuseOutcome::kRejectedTooOld:
      return "rejected_too_old";
    case FuseOutcome::kRejectedNotInitialized:
      return "rejected_not_initialized";
    case FuseOutcome::kRejectedNumerical:
      return "rejected_numerical";
    case FuseOutcome::kTimeWentBackwards:
      return "time_went_backwards";
    case FuseOutcome::kTimeJumpedForward:
      return "time_jumped_forward";
    case FuseOutcome::kRejectedStale:
      return "rejected_stale";
  }
  return "unknown";
}

}  // namespace gmm_localization
