/// A BSP's planes and view box on disk, shared by .vcells and .pvs.
#include "viewcells/bsp/bsp_io.h"

#include <cmath>

namespace viewcells {

void put_planes(ByteWriter& w, const std::vector<Plane>& planes) {
  w.put<uint64_t>(planes.size());
  for (const Plane& p : planes) {
    w.put<int32_t>(p.axis);
    w.put(p.normal);
    w.put(p.offset);
    for (const Vec3& q : p.points) w.put(q);
  }
}

std::vector<Plane> get_planes(ByteReader& r, uint64_t max_items) {
  const uint64_t count = r.get<uint64_t>();
  if (count < 6 || count > max_items) r.fail("invalid plane count");
  std::vector<Plane> planes(count);
  for (Plane& p : planes) {
    p.axis = r.get<int32_t>();
    p.normal = r.get<Vec3>();
    p.offset = r.get<double>();
    for (Vec3& q : p.points) q = r.get<Vec3>();
    if (p.axis < -1 || p.axis > 2 || !is_finite(p.normal) || !std::isfinite(p.offset)) r.fail("invalid plane");
    // A geometry-aligned plane's side is decided exactly from its points: they must be numbers.
    if (p.axis < 0 && !(is_finite(p.points[0]) && is_finite(p.points[1]) && is_finite(p.points[2])))
      r.fail("invalid plane");
  }
  return planes;
}

Box3 get_view_box(ByteReader& r) {
  Box3 b;
  b.lo = r.get<Vec3>();
  b.hi = r.get<Vec3>();
  if (!(b.volume() > 0) || !is_finite(b.lo) || !is_finite(b.hi)) r.fail("invalid view box");
  return b;
}

}  // namespace viewcells
