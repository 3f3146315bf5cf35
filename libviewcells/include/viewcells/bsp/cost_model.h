#pragma once
/// The render-cost model (view-cell-construction paper, section 3.3; DESIGN.md):
/// r(o) = max(a, b * t_o, c * p_o), r(PVS) = sum of r(o), c(S) = sum_i p(i) r(PVS_i) with
/// p(i) = V_i / V.
#include <string>
#include <vector>

#include "viewcells/scene/scene.h"

namespace viewcells {

struct CostModel {
  /// Cost of any object, however small: the fixed per-draw overhead, in triangle-equivalents.
  double a = 100.0;
  /// Cost per triangle.
  double b = 1.0;
  /// Cost per projected pixel. The pixel term needs a renderer's estimate per cell and is not
  /// computed yet: values other than 0 are rejected (see per_object_costs).
  double c = 0.0;
};

/// r(o) for every object of the scene. Throws Error when c != 0 (pixel term not available).
std::vector<double> per_object_costs(const Scene& scene, const CostModel& model);

}  // namespace viewcells
