#pragma once
/// Numbers and boxes as text for log lines and messages: fixed decimals.
#include <sstream>
#include <string>

#include "viewcells/core/vec3.h"

namespace viewcells {

inline std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
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
