#pragma once
/// Double-precision 3-vectors and axis-aligned boxes. Geometry is kept in double; only the
/// ray caster converts to float, in a local frame (see raycast/embree_caster.cpp).
#include <algorithm>
#include <utility>
#include <cmath>
#include <limits>

namespace viewcells {

struct Vec3 {
  double x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
  constexpr bool operator!=(const Vec3& o) const { return !(*this == o); }
};

constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(const Vec3& v) { return v / length(v); }
/// Unit vectors u, v perpendicular to the unit vector n with u x v = n (built from the axis
/// n is least aligned with, so they are well conditioned for any n).
inline void orthonormal_basis(const Vec3& n, Vec3& u, Vec3& v) {
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const Vec3 e = ax <= ay && ax <= az ? Vec3{1, 0, 0} : (ay <= az ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  u = normalize(cross(n, e));
  v = cross(n, u);
}
constexpr Vec3 min(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
constexpr Vec3 max(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline bool is_finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Axis-aligned box; default-constructed boxes are empty (lo > hi).
struct Box3 {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()};

  constexpr Box3() = default;
  constexpr Box3(const Vec3& lo_, const Vec3& hi_) : lo(lo_), hi(hi_) {}

  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  void extend(const Vec3& p) { lo = min(lo, p); hi = max(hi, p); }
  void extend(const Box3& b) { lo = min(lo, b.lo); hi = max(hi, b.hi); }
  Vec3 extent() const { return hi - lo; }
  Vec3 center() const { return (lo + hi) * 0.5; }
  double diagonal() const { return empty() ? 0.0 : length(hi - lo); }
  double volume() const {
    if (empty()) return 0.0;
    const Vec3 e = extent();
    return e.x * e.y * e.z;
  }
  /// Inclusive containment with an absolute tolerance.
  bool contains(const Vec3& p, double tol = 0.0) const {
    return p.x >= lo.x - tol && p.x <= hi.x + tol && p.y >= lo.y - tol && p.y <= hi.y + tol &&
           p.z >= lo.z - tol && p.z <= hi.z + tol;
  }
  bool operator==(const Box3& o) const { return lo == o.lo && hi == o.hi; }
};

/// Euclidean distance between two boxes (0 when they touch or overlap).
inline double box_distance(const Box3& a, const Box3& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]});
    s += gap * gap;
  }
  return std::sqrt(s);
}

/// Parametric interval [t0, t1] of the line o + t*d inside box b (slab test).
/// Returns false when the line misses the box. Zero direction components are handled.
/// Inline: the sampler calls it once per sample.
inline bool clip_line_to_box(const Box3& b, const Vec3& o, const Vec3& d, double& t0, double& t1) {
  t0 = -std::numeric_limits<double>::infinity();
  t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
      continue;
    }
    const double inv = 1.0 / d[a];
    double ta = (b.lo[a] - o[a]) * inv;
    double tb = (b.hi[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

}  // namespace viewcells
