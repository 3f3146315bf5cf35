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
  return "[" + fmt(b.lo.x) + ", " + fmt(b.lo.y) + ", " + fmt(b.lo.z) + "] - [" + fmt(b.hi.x) + ", " +
         fmt(b.hi.y) + ", " + fmt(b.hi.z) + "]";
}

}  // namespace viewcells
