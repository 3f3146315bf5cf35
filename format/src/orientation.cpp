// The exact fallback of the orientation predicate (orientation.h): the determinant as an exact
// integer sum. Compiled with -ffp-contract=off (format/CMakeLists.txt): rounded products and
// sums, never fused ones.
#include "viewcells/format/orientation.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace viewcells::format {

namespace {

/// Signed integers of any size (32-bit limbs, least significant first), for the exact
/// fallback: a double is an integer times a power of two, so with every coordinate of a
/// predicate on the grid of the smallest power among them, the determinant is an exact
/// integer sum whatever the magnitudes (no overflow, no underflow, denormals included).
struct BigInt {
  bool negative = false;
  std::vector<uint32_t> limbs;  // magnitude; empty for zero

  void trim() {
    while (!limbs.empty() && limbs.back() == 0) limbs.pop_back();
    if (limbs.empty()) negative = false;
  }
  /// |m| * 2^shift, with the sign of `negative`.
  static BigInt from(uint64_t m, int shift, bool negative) {
    BigInt b;
    b.negative = negative;
    b.limbs.assign(static_cast<size_t>(shift / 32) + 3, 0);
    const int bit = shift % 32;  // m < 2^53, so m 2^bit < 2^85: three limbs
    const uint64_t low = m << bit, high = bit ? m >> (64 - bit) : 0;
    b.limbs[shift / 32] = static_cast<uint32_t>(low);
    b.limbs[shift / 32 + 1] = static_cast<uint32_t>(low >> 32);
    b.limbs[shift / 32 + 2] = static_cast<uint32_t>(high);
    b.trim();
    return b;
  }
};

int compare_magnitude(const BigInt& a, const BigInt& b) {
  if (a.limbs.size() != b.limbs.size()) return a.limbs.size() < b.limbs.size() ? -1 : 1;
  for (size_t k = a.limbs.size(); k-- > 0;)
    if (a.limbs[k] != b.limbs[k]) return a.limbs[k] < b.limbs[k] ? -1 : 1;
  return 0;
}

BigInt multiply(const BigInt& a, const BigInt& b) {
  BigInt r;
  if (a.limbs.empty() || b.limbs.empty()) return r;
  r.negative = a.negative != b.negative;
  r.limbs.assign(a.limbs.size() + b.limbs.size(), 0);
  for (size_t i = 0; i < a.limbs.size(); ++i) {
    uint64_t carry = 0;
    for (size_t j = 0; j < b.limbs.size(); ++j) {
      const uint64_t t = static_cast<uint64_t>(a.limbs[i]) * b.limbs[j] + r.limbs[i + j] + carry;
      r.limbs[i + j] = static_cast<uint32_t>(t);
      carry = t >> 32;
    }
    r.limbs[i + b.limbs.size()] = static_cast<uint32_t>(carry);
  }
  r.trim();
  return r;
}

BigInt add(const BigInt& a, const BigInt& b) {
  BigInt r;
  if (a.negative == b.negative) {
    r.negative = a.negative;
    r.limbs.assign(std::max(a.limbs.size(), b.limbs.size()) + 1, 0);
    uint64_t carry = 0;
    for (size_t k = 0; k + 1 < r.limbs.size(); ++k) {
      const uint64_t t = carry + (k < a.limbs.size() ? a.limbs[k] : 0) + (k < b.limbs.size() ? b.limbs[k] : 0);
      r.limbs[k] = static_cast<uint32_t>(t);
      carry = t >> 32;
    }
    r.limbs.back() = static_cast<uint32_t>(carry);
  } else {
    const bool a_larger = compare_magnitude(a, b) >= 0;
    const BigInt& big = a_larger ? a : b;
    const BigInt& small = a_larger ? b : a;
    r.negative = big.negative;
    r.limbs.assign(big.limbs.size(), 0);
    int64_t borrow = 0;
    for (size_t k = 0; k < big.limbs.size(); ++k) {
      int64_t t = static_cast<int64_t>(big.limbs[k]) - (k < small.limbs.size() ? small.limbs[k] : 0) - borrow;
      borrow = t < 0;
      if (t < 0) t += int64_t{1} << 32;
      r.limbs[k] = static_cast<uint32_t>(t);
    }
  }
  r.trim();
  return r;
}


}  // namespace

/// The sign of det [a 1; b 1; c 1; d 1], exactly: the 24 signed triple products of the
/// coordinates, each coordinate an integer on the grid 2^emin of the smallest among them.
int exact_det4_sign(const Vec* points[4]) {
  int emin = std::numeric_limits<int>::max();
  for (int i = 0; i < 4; ++i)
    for (double x : points[i]->v)
      if (x != 0) {
        int e = 0;
        std::frexp(x, &e);
        emin = std::min(emin, e - 53);
      }
  if (emin == std::numeric_limits<int>::max()) return 0;  // every point at the origin
  BigInt q[4][3];
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      const double x = points[i]->v[k];
      if (x == 0) continue;
      int e = 0;
      const double f = std::frexp(x, &e);  // x = f 2^e, 0.5 <= |f| < 1
      const uint64_t m = static_cast<uint64_t>(std::ldexp(std::fabs(f), 53));  // exact: 53 bits
      q[i][k] = BigInt::from(m, e - 53 - emin, x < 0);
    }
  // Cofactors along the column of ones: det4 = -det[b;c;d] + det[a;c;d] - det[a;b;d] + det[a;b;c].
  static constexpr int kRows[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
  BigInt sum;
  for (int minor = 0; minor < 4; ++minor)
    for (int p = 0; p < 6; ++p) {
      BigInt t = multiply(multiply(q[kRows[minor][0]][kPerm[p][0]], q[kRows[minor][1]][kPerm[p][1]]),
                          q[kRows[minor][2]][kPerm[p][2]]);
      // The minor's sign (- for 0 and 2) times the permutation's (the first three are even).
      if (((minor % 2 == 0) == (p < 3)) && !t.limbs.empty()) t.negative = !t.negative;
      sum = add(sum, t);
    }
  return sum.limbs.empty() ? 0 : (sum.negative ? -1 : 1);
}

}  // namespace viewcells::format
