#include "viewcells/bsp/cost_model.h"

#include <algorithm>
#include <cmath>

#include "viewcells/core/error.h"

namespace viewcells {

std::vector<double> per_object_costs(const Scene& scene, const CostModel& model) {
  if (!(model.a >= 0) || !(model.b >= 0) || !std::isfinite(model.a) || !std::isfinite(model.b))
    throw Error("cost model: a and b must be finite and non-negative");
  if (model.c != 0.0)
    throw Error("cost model: the pixel term (c > 0) is not implemented yet; use c = 0");
  std::vector<double> r(scene.objects.size());
  for (size_t o = 0; o < r.size(); ++o)
    r[o] = std::max(model.a, model.b * static_cast<double>(scene.objects[o].triangle_count));
  return r;
}

}  // namespace viewcells
