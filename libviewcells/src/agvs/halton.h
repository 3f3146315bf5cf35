#pragma once
// AGVS paper 4.3 (stationary ray distributions): the quasi-random numbers they draw from.
// Halton sequences with seeded rotations, and uniform directions on the sphere.
#include <cmath>
#include <cstdint>
#include <numbers>

#include "viewcells/core/rng.h"
#include "viewcells/core/vec3.h"

namespace viewcells::agvs_detail {

/// Radical inverse of i in base b: the Halton sequence's coordinate.
inline double radical_inverse(uint64_t i, uint32_t b) {
  double inv = 1.0 / b, f = inv, r = 0;
  while (i > 0) {
    r += f * static_cast<double>(i % b);
    i /= b;
    f *= inv;
  }
  return r;
}

/// Halton point `i` of a stream: coordinates in bases 2, 3, 5, ..., each rotated by a seeded
/// offset (Cranley-Patterson), so that seeds give different but equally even sequences.
struct Halton {
  static constexpr uint32_t kBases[7] = {2, 3, 5, 7, 11, 13, 17};
  double offset[7];
  Halton(uint64_t seed, uint64_t stream) {
    Rng rng(seed, stream);
    for (double& o : offset) o = rng.uniform();
  }
  double at(uint64_t i, int dim) const {
    const double x = radical_inverse(i + 1, kBases[dim]) + offset[dim];
    return x - std::floor(x);
  }
};

inline Vec3 sphere_direction(double u1, double u2) {
  const double phi = 2 * std::numbers::pi * u1, cos_theta = 1 - 2 * u2;
  const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

}  // namespace viewcells::agvs_detail
