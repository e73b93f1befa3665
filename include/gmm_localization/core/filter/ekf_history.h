#pragma once
// Bounded, time-ordered history of the EKF for delayed measurements (robot_localization's idea
// of keeping past states and measurements, our own structure).
//
// It holds a base state and, after it, one entry per measurement offered in stamp order: the
// measurement and the state right after it (posterior if fused, else the prediction to its
// stamp). A late measurement rewinds to the last entry at or before its stamp; the caller then
// fuses it and re-fuses the removed entries in order. Equal stamps keep arrival order.

#include <cstddef>
#include <deque>
#include <vector>

#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

struct HistoryEntry {
  EkfMeasurement measurement;
  EkfState state;      ///< at measurement.stamp_s, after the measurement
  bool fused = false;  ///< false if the update rejected it (kept: a replay may accept it)
};

class EkfHistory {
 public:
  /// Drops every entry; base becomes the starting state.
  void clear(const EkfState& base);

  /// Newest state: the last entry's, or the base when empty.
  const EkfState& latest() const { return entries_.empty() ? base_ : entries_.back().state; }
  /// Oldest state still held (measurements before its time cannot be inserted).
  const EkfState& base() const { return base_; }
  std::size_t size() const { return entries_.size(); }

  /// Appends an entry; its stamp must be >= latest().time_s.
  void append(HistoryEntry entry) { entries_.push_back(std::move(entry)); }

  /// Removes and returns, oldest first, the entries with stamp > time_s, so that latest() is
  /// the state to restart from. Requires time_s >= base().time_s.
  std::vector<HistoryEntry> rewindTo(double time_s);

  /// The last state with time <= time_s (an entry's, else the base), or nullptr when time_s is
  /// before the base.
  const EkfState* stateAtOrBefore(double time_s) const;

  /// Folds into the base the oldest entries while their stamp is < oldest_time_s or there are
  /// more than max_entries.
  void trim(double oldest_time_s, std::size_t max_entries);

 private:
  EkfState base_;
  std::deque<HistoryEntry> entries_;
};

}  // namespace gmm_localization
