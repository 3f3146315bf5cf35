#pragma once
/// A BSP's pieces on disk, shared by the hierarchy file (.vcells) and the .pvs file: the split
/// planes (count, then axis, normal, offset and defining points of each) and a validated view
/// box, in the toolkit's binary container (core/binary_file.h).
#include <cstdint>
#include <vector>

#include "viewcells/bsp/plane.h"
#include "viewcells/core/binary_file.h"

namespace viewcells {

void put_planes(ByteWriter& w, const std::vector<Plane>& planes);
std::vector<Plane> get_planes(ByteReader& r, uint64_t max_items);
Box3 get_view_box(ByteReader& r);

}  // namespace viewcells
