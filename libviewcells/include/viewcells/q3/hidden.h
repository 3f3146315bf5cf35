#pragma once
/// A Quake 3 map's solid space for proving objects hidden (issue 65): the BSP q3map2 built, its
/// leaves without a cluster solid (the structural brushes, and the outside of a sealed map),
/// and the map's spawn points as where viewers are, for finding a leak.
#include <memory>

#include "viewcells/hidden/hidden_space.h"
#include "viewcells/q3/bsp_file.h"

namespace viewcells {

/// The map's BSP as a SolidBsp over the map's bounds (with a margin around `scene`'s).
SolidBsp q3_solid_bsp(const Q3Map& map, const Scene& scene);
/// What the map's portals prove hidden, for the objects of `scene` (the map's surfaces).
std::shared_ptr<const HiddenSpace> q3_hidden_space(const Q3Map& map, const Scene& scene);

}  // namespace viewcells
