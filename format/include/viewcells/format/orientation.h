#pragma once
// The orientation predicate a reader of a .pvs file locates points with against its general
// (not axis-aligned) planes, each stored as three points: the sign CGAL's orientation(a, b, c,
// d) gives (the sign the toolkit's subdivision used), exactly. Part of the format: a reader that
// rounds differently puts points near a plane into another cell. A floating-point filter
// decides almost always (inline: it is on location's path); the exact integer determinant
// (orientation.cpp) decides the rest.
#include <cmath>

namespace viewcells::format {

/// A point of the file, in double precision.
struct Vec {
  double v[3];
};

/// A general plane as the file stores it: the three points that define it (the toolkit's
/// Plane::points).
struct GeneralPlane {
  Vec a, b, c;
};

/// The sign of det [a 1; b 1; c 1; d 1], exactly (orientation.cpp).
int exact_det4_sign(const Vec* points[4]);

/// The floating-point filter of orientation(): the sign of det [b - a; c - a; d - a] when
/// Shewchuk's error bound decides it, else 0 (undecided, or out of double's range).
inline int filtered_orientation(const GeneralPlane& pl, const Vec& d) {
  const double* a = pl.a.v;
  const double* b = pl.b.v;
  const double* c = pl.c.v;
  const double adx = a[0] - d.v[0], bdx = b[0] - d.v[0], cdx = c[0] - d.v[0];
  const double ady = a[1] - d.v[1], bdy = b[1] - d.v[1], cdy = c[1] - d.v[1];
  const double adz = a[2] - d.v[2], bdz = b[2] - d.v[2], cdz = c[2] - d.v[2];
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  // det [a - d; b - d; c - d] = -det [b - a; c - a; d - a].
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
  constexpr double eps = 1.1102230246251565e-16;  // 2^-53
  const double bound = 2 * (7.0 + 56.0 * eps) * eps * permanent;  // twice Shewchuk's A bound
  // The bound holds without underflow or overflow: far from both, the filter decides.
  if (permanent > 1e-250 && permanent < 1e250) {
    if (det > bound) return -1;
    if (-det > bound) return 1;
  }
  return 0;
}

/// Sign of det [b - a; c - a; d - a] (CGAL's orientation(a, b, c, d)), exactly: the filter,
/// and the exact integer determinant when it cannot decide.
inline int orientation(const GeneralPlane& pl, const Vec& d) {
  if (const int sign = filtered_orientation(pl, d)) return sign;
  // det [a 1; b 1; c 1; d 1] = -det [b - a; c - a; d - a].
  const Vec* points[4] = {&pl.a, &pl.b, &pl.c, &d};
  return -exact_det4_sign(points);
}

}  // namespace viewcells::format
