#pragma once
// Deterministic randomness for the simulator. Two kinds:
//  - Rng: a sequential generator (splitmix64 stream) for building the town, routes and actors,
//    where draws happen in one fixed order.
//  - hash*: counter-based draws keyed by integers (sensor, revolution, firing, laser, purpose),
//    so a ray's noise does not depend on which thread traced it or in which order.
// Both are identical on every platform (no std::distribution, whose output is unspecified).

#include <cmath>
#include <cstdint>

namespace gmm_localization {
namespace sim {

inline uint64_t splitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Hash of a sequence of keys (order matters).
inline uint64_t hashKeys(uint64_t a) { return splitMix64(a); }
template <typename... Rest>
inline uint64_t hashKeys(uint64_t a, Rest... rest) {
  return splitMix64(a ^ (hashKeys(static_cast<uint64_t>(rest)...) * 0xD6E8FEB86659FD93ull));
}

/// Uniform in [0, 1) from a 64-bit hash.
inline double unitFromHash(uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

template <typename... Keys>
inline double hashUniform(Keys... keys) {
  return unitFromHash(hashKeys(static_cast<uint64_t>(keys)...));
}

/// Standard normal from keys (Box-Muller on two derived uniforms).
template <typename... Keys>
inline double hashNormal(Keys... keys) {
  const uint64_t h = hashKeys(static_cast<uint64_t>(keys)...);
  const double u1 = 1.0 - unitFromHash(splitMix64(h ^ 0x1234567ull));  // (0, 1]
  const double u2 = unitFromHash(splitMix64(h ^ 0x89ABCDEull));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

/// Sequential generator; copyable, so a sub-stream can be forked with fork(key).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(splitMix64(seed)) {}
  uint64_t next() {
    state_ += 0x9E3779B97F4A7C15ull;
    uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return unitFromHash(next()); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [0, n); n > 0.
  int uniformInt(int n) { return static_cast<int>(uniform() * n); }
  bool bernoulli(double p) { return uniform() < p; }
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  /// An independent generator derived from this one's seed and a key (does not advance this).
  Rng fork(uint64_t key) const { return Rng(hashKeys(state_, key)); }

 private:
  uint64_t state_;
};

}  // namespace sim
}  // namespace gmm_localization
