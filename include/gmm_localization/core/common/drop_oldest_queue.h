#pragma once
// A bounded FIFO that makes room by dropping its oldest entries, counting them: the matcher's
// scan queue (a slow match leaves a backlog that faster ones drain; a persistent overload
// costs the oldest scans, never unbounded latency). Not synchronised: the owner locks.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>

namespace gmm_localization {

template <typename T>
class DropOldestQueue {
 public:
  explicit DropOldestQueue(size_t capacity) : capacity_(std::max<size_t>(1, capacity)) {}

  /// Appends `item`; returns how many of the oldest were dropped to make room (0 or more).
  size_t push(T item) {
    size_t dropped = 0;
    while (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped;
    }
    items_.push_back(std::move(item));
    dropped_total_ += dropped;
    return dropped;
  }
  /// Drops every entry (counted like the others); returns how many.
  size_t clear() {
    const size_t dropped = items_.size();
    items_.clear();
    dropped_total_ += dropped;
    return dropped;
  }
  /// Removes and returns the oldest entry. Precondition: !empty().
  T pop() {
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }
  bool empty() const { return items_.empty(); }
  size_t size() const { return items_.size(); }
  size_t capacity() const { return capacity_; }
  uint64_t droppedTotal() const { return dropped_total_; }

 private:
  size_t capacity_;
  std::deque<T> items_;
  uint64_t dropped_total_ = 0;
};

}  // namespace gmm_localization
