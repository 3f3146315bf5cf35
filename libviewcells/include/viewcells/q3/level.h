#pragma once
/// A Quake 3 map as a level (level/level.h): the adapter the pipeline meets a map through, with
/// its view space (non-solid leaves and the play space), what its BSP proves hidden, q3map2's
/// PVS to measure against, its play space to compare with one found from floors, and what
/// `info` says of it. Front ends register it (register_q3_map_format, q3/bsp_file.h).
#include <memory>
#include <string>

#include "viewcells/level/level.h"
#include "viewcells/q3/bsp_file.h"

namespace viewcells {

/// Whether `path` names a Quake 3 map (.bsp, any case).
bool is_q3_map(const std::string& path);

/// The map a level brings, when it is a Quake 3 map's (for map-specific studies and tests);
/// null otherwise.
std::shared_ptr<const Q3Map> q3_map_of(const LevelData* level);

/// The level of a map read already.
std::shared_ptr<const LevelData> q3_level(std::shared_ptr<const Q3Map> map);

}  // namespace viewcells
