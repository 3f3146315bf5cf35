#pragma once
/// The bake's three answers per (view cell, object) pair (issue 65): proven visible by rays,
/// proven hidden by the scene's solid space, undecided; and the conservative mode's PVSs.
#include <optional>
#include <vector>

#include "viewcells/pipeline/bake.h"

namespace viewcells::pipeline {

/// What `space` proves for the view cells of `bsp` (a leaf's cell is leaf_cell[node]), with
/// each cell's volume: before any sampling, since it needs none. Cells not begun by `deadline`
/// prove nothing (HiddenProof::cells_unproven).
struct CellProof {
  HiddenProof proof;
  std::vector<double> volume;
};
CellProof prove_cells(const BakeConfig& config, const HiddenSpace& space, const Subdivision& bsp,
                      const std::vector<int32_t>& leaf_cell, size_t cell_count, const Deadline& deadline);

/// Rays aimed at the undecided pairs (BakeConfig::aimed_rays).
struct AimedRays {
  uint64_t pairs = 0, rays = 0, found = 0;
  double seconds = 0;
};
/// Casts BakeConfig::aimed_rays at each pair of `cells` that `proved` leaves open and `lists`
/// does not hold (rendered objects only): every pair a ray sees joins its cell's list. Cells
/// not begun by `deadline` get none. The same for any thread count (a stream per cell).
AimedRays aim_at_undecided(const BakeConfig& config, const LoadedScene& loaded, const HiddenSpace& space,
                           const CellProof& proved, const CellLocator& cells,
                           std::vector<std::vector<uint32_t>>& lists, const Deadline& deadline, const Log& log);

/// Sorts the pairs of `lists` (the sampled PVSs) into the classes by `proved`, and with
/// config.conservative adds the undecided pairs to `lists`. Costs are weighed by the cameras'
/// frames per cell when `cams` is given, else by the cells' volumes.
BakeResult::HiddenClasses hidden_classes(const BakeConfig& config, const LoadedScene& loaded, const HiddenSpace& space,
                                         const CellProof& proved, const AimedRays& aimed,
                                         const std::optional<CameraSet>& cams,
                                         std::vector<std::vector<uint32_t>>& lists, const Log& log);

}  // namespace viewcells::pipeline
