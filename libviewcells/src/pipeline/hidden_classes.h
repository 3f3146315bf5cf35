#pragma once
/// The bake's three answers per (view cell, object) pair (issue 65): proven visible by rays,
/// proven hidden by the scene's solid space, undecided; and the conservative mode's PVSs.
#include <optional>
#include <vector>

#include "viewcells/pipeline/bake.h"

namespace viewcells::pipeline {

/// Proves what `space` can for the view cells of `bsp` (a leaf's cell is leaf_cell[node]), sorts
/// the pairs of `lists` (the sampled PVSs) into the classes, and with config.conservative adds
/// the undecided pairs to `lists`. Costs are weighed by the cameras' frames per cell when `cams`
/// is given, else by the cells' volumes.
BakeResult::HiddenClasses prove_hidden_classes(const BakeConfig& config, const LoadedScene& loaded,
                                               const HiddenSpace& space, const Subdivision& bsp,
                                               const std::vector<int32_t>& leaf_cell,
                                               const std::optional<CameraSet>& cams,
                                               std::vector<std::vector<uint32_t>>& lists, const Log& log);

}  // namespace viewcells::pipeline
