// Deterministic random numbers for the simulator. Same seed -> same worlds and scans on every
// platform (std:: distributions are implementation-defined, so they are not used). The range
// noise is counter-based: the noise of ray k depends only on (seed, k), so scans are
// reproducible whatever the order rays are cast in.
#pragma once

#include <cmath>
#include <cstdint>

namespace ladar_perception {
namespace sim {

// SplitMix64 finaliser: a well-mixed 64-bit hash.
inline uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform in (0, 1) from 53 bits of a hash (never exactly 0, so log() is safe).
inline double unitFromBits(uint64_t bits) {
  return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Standard normal for ray `counter` of a stream `seed` (Box-Muller on two hashed uniforms).
inline double gaussianAt(uint64_t seed, uint64_t counter) {
  const uint64_t a = mix64(seed ^ mix64(counter));
  const uint64_t b = mix64(a);
  const double u1 = unitFromBits(a);
  const double u2 = unitFromBits(b);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// The same stream as a Box-Muller pair per two counters: counter 2n is the cosine, 2n + 1 the
// sine of pair n, so walking counters in order costs one log, sqrt and sincos per two
// values. at() is a pure function of (seed, counter); the cache only saves work.
class GaussianStream {
 public:
  explicit GaussianStream(uint64_t seed) : seed_(seed) {}
  double at(uint64_t counter) {
    const uint64_t pair = counter >> 1;
    if (pair != pair_ || !valid_) {
      const uint64_t a = mix64(seed_ ^ mix64(pair));
      const double radius = std::sqrt(-2.0 * std::log(unitFromBits(a)));
      const double angle = 6.283185307179586 * unitFromBits(mix64(a));
      cos_ = radius * std::cos(angle);
      sin_ = radius * std::sin(angle);
      pair_ = pair;
      valid_ = true;
    }
    return (counter & 1) ? sin_ : cos_;
  }

 private:
  uint64_t seed_;
  uint64_t pair_ = 0;
  bool valid_ = false;
  double cos_ = 0.0, sin_ = 0.0;
};

// A small sequential generator for world generation.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(mix64(seed ^ 0x5eed5eed5eedULL)) {}
  uint64_t next() { state_ += 0x9e3779b97f4a7c15ULL; return mix64(state_); }
  double uniform() { return unitFromBits(next()); }                      // (0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int uniformInt(int lo, int hi) {                                       // [lo, hi]
    return lo + static_cast<int>(uniform() * (hi - lo + 1)) % (hi - lo + 1);
  }
  double gaussian() {
    const double u1 = uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  uint64_t state_;
};

}  // namespace sim
}  // namespace ladar_perception
