// AGVS paper 4.1, equation 2: a visibility sample's contribution, the PVS entries it adds to
// the cells its segment pierces.
#include "solver_impl.h"

namespace viewcells {

uint32_t contribute(GlobalPvs& pvs, const std::vector<int32_t>& cells, uint32_t object_a, uint32_t object_b,
                    bool contributed[2], int32_t origin_cell, bool at_origin[2]) {
  const uint32_t objs[2] = {object_a, object_b};
  uint32_t gain = 0;
  for (int32_t cell : cells)
    gain += agvs_detail::contribute_in_cell([&](uint32_t o) { return pvs.insert(static_cast<uint32_t>(cell), o); },
                                            objs, cell == origin_cell, contributed, at_origin);
  // Both ends see the same object: both rays were wrong pixels before.
  if (at_origin && objs[0] == objs[1] && objs[0] != kNoObject) at_origin[1] = at_origin[0];
  return gain;
}

}  // namespace viewcells
