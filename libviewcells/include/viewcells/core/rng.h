#pragma once
/// Deterministic random numbers. Streams are keyed by (seed, stream index) rather than by
/// thread, so every parallel stage produces the same output for any thread count.
#include <cstdint>

namespace viewcells {

/// SplitMix64 finaliser: a bijective 64-bit mix, used to derive independent stream seeds.
constexpr uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// xoshiro256** generator; cheap, 256-bit state, good statistical quality.
class Rng {
 public:
  /// A stream determined only by (seed, stream).
  explicit Rng(uint64_t seed, uint64_t stream = 0) {
    uint64_t x = mix64(seed ^ mix64(stream + 0x632be59bd9b4e019ULL));
    for (auto& w : s_) w = x = mix64(x);
  }
  uint64_t next_u64() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n); n > 0.
  uint64_t below(uint64_t n) { return static_cast<uint64_t>(uniform() * static_cast<double>(n)) % n; }

 private:
  static constexpr uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

}  // namespace viewcells
