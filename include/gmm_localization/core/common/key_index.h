#pragma once
// Dense indices for 64-bit keys: an open-addressing hash table (linear probing, power-of-two
// capacity, grown at half load) that numbers keys 0, 1, 2, ... in first-seen order. Small and
// flat so that the per-scan tables of the scan filter stay in cache (a node-based
// std::unordered_map, or a table sized for every input point, does not).

#include <cstdint>
#include <vector>

namespace gmm_localization {

class KeyIndex {
 public:
  /// expected: the number of distinct keys expected (the table grows past it as needed).
  explicit KeyIndex(size_t expected = 0) { rehash(capacityFor(expected)); }

  /// Index of `key` (< 2^63), numbering it size() when new (then `inserted` is true).
  uint32_t insert(uint64_t key, bool& inserted) {
    if (2 * (size_ + 1) > slots_.size()) rehash(2 * slots_.size());
    const uint64_t k = key | kTag;  // so that no stored key is 0 (the empty mark)
    for (size_t h = slot(k);; h = (h + 1) & (slots_.size() - 1)) {
      Slot& s = slots_[h];
      if (s.key == k) {
        inserted = false;
        return s.index;
      }
      if (s.key == 0) {
        s = {k, static_cast<uint32_t>(size_)};
        inserted = true;
        return static_cast<uint32_t>(size_++);
      }
    }
  }
  /// Index of `key` (< 2^63), or -1 when absent.
  int64_t find(uint64_t key) const {
    const uint64_t k = key | kTag;
    for (size_t h = slot(k);; h = (h + 1) & (slots_.size() - 1)) {
      const Slot& s = slots_[h];
      if (s.key == k) return s.index;
      if (s.key == 0) return -1;
    }
  }
  size_t size() const { return size_; }
  /// Asks the memory for the slot where a lookup of `key` starts.
  void prefetch(uint64_t key) const { __builtin_prefetch(&slots_[slot(key | kTag)]); }

 private:
  struct Slot {
    uint64_t key = 0;
    uint32_t index = 0;
  };
  static constexpr uint64_t kTag = uint64_t{1} << 63;

  static size_t capacityFor(size_t n) {
    size_t c = 64;
    while (c < 2 * n) c <<= 1;
    return c;
  }
  size_t slot(uint64_t k) const {  // Fibonacci hashing: the product's top bits
    return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void rehash(size_t capacity) {
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(capacity, Slot{});
    shift_ = 64;
    for (size_t c = capacity; c > 1; c >>= 1) --shift_;
    for (const Slot& s : old) {
      if (s.key == 0) continue;
      size_t h = slot(s.key);
      while (slots_[h].key != 0) h = (h + 1) & (capacity - 1);
      slots_[h] = s;
    }
  }

  std::vector<Slot> slots_;
  int shift_ = 58;  ///< 64 - log2(capacity)
  size_t size_ = 0;
};

}  // namespace gmm_localization
