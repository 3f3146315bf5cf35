#pragma once
/// Numbers and boxes as text for log lines and messages: fixed decimals.
#include <sstream>
#include <string>

#include "viewcells/core/vec3.h"

namespace viewcells {

/// Fixed decimals; magnitudes from 1e15 up in scientific notation (a fixed 1e308 has 309 digits).
inline std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.setf(v < 1e15 && v > -1e15 ? std::ios::fixed : std::ios::scientific, std::ios::floatfield);
  os.precision(precision);
  os << v;
  return os.str();
}

inline std::string describe_box(const Box3& b) {
  // By appends: gcc 12 warns (-Wrestrict, a false alarm) on "literal" + a temporary string.
  std::string s = "[";
  s += fmt(b.lo.x) + ", " + fmt(b.lo.y) + ", " + fmt(b.lo.z);
  s += "] - [";
  s += fmt(b.hi.x) + ", " + fmt(b.hi.y) + ", " + fmt(b.hi.z);
  s += "]";
  return s;
}

}  // namespace viewcells
