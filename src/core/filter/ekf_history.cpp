#include "gmm_localization/core/filter/ekf_history.h"

#include <algorithm>
#include <iterator>

namespace gmm_localization {
namespace {

// First entry whose stamp is strictly after time_s.
template <typename It>
It firstAfter(It begin, It end, double time_s) {
  return std::upper_bound(begin, end, time_s, [](double t, const HistoryEntry& e) {
    return t < e.measurement.stamp_s;
  });
}

}  // namespace

void EkfHistory::clear(const EkfState& base) {
  base_ = base;
  entries_.clear();
}

std::vector<HistoryEntry> EkfHistory::rewindTo(double time_s) {
  const auto first = firstAfter(entries_.begin(), entries_.end(), time_s);
  std::vector<HistoryEntry> removed(std::make_move_iterator(first),
                                    std::make_move_iterator(entries_.end()));
  entries_.erase(first, entries_.end());
  return removed;
}

const EkfState* EkfHistory::stateAtOrBefore(double time_s) const {
  if (time_s < base_.time_s) return nullptr;
  const auto first = firstAfter(entries_.begin(), entries_.end(), time_s);
  return first == entries_.begin() ? &base_ : &std::prev(first)->state;
}

void EkfHistory::trim(double oldest_time_s, std::size_t max_entries) {
  while (!entries_.empty() &&
         (entries_.front().measurement.stamp_s < oldest_time_s || entries_.size() > max_entries)) {
    base_ = entries_.front().state;
    entries_.pop_front();
  }
}

}  // namespace gmm_localization
