#pragma once
/// A Quake 3 map as a ViewSpace (viewspace/view_space.h): viewpoints in its non-solid space
/// (q3/view_space.h), cells weighed by their non-solid volume, cameras at players' eyes
/// (q3/play.h); its play space (the leaves a player's eye can reach) is a ViewSpace of its own,
/// which also draws the subdivision's viewpoints and AGVS's points there.
#include <memory>

#include "viewcells/viewspace/view_space.h"
#include "viewcells/q3/bsp_file.h"

namespace viewcells {

/// The view space of `map` (not null).
std::shared_ptr<const ViewSpace> q3_map_view_space(std::shared_ptr<const Q3Map> map);

}  // namespace viewcells
