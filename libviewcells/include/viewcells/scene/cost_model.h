#pragma once
/// The render-cost model (view-cell-construction paper, section 3.3; DESIGN.md):
/// r(o) = max(a, b * t_o, c * p_o), r(PVS) = sum of r(o), c(S) = sum_i p(i) r(PVS_i) with
/// p(i) = V_i / V.
///
/// The pixel term p_o depends on where the viewer is, so with c > 0 the cost of an object
/// depends on the cell: p_o is estimated from some points of the cell, each seeing the object
/// as a convex body of its surface area at the distance of its bounding box, on a screen of
/// the model's size and field of view. The points are the centres of the eight octants of the
/// cell's bounding box (the same rule for BSP leaves, merged cells and any other partition):
/// a midpoint rule for the mean over the cell, so a cell and its halves estimate alike, where
/// corner points would bias small cells upwards. With c = 0 (the default) nothing of this is
/// computed and r(o) is one number per object.
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/core/vec3.h"
#include "viewcells/scene/scene.h"

namespace viewcells {

struct CostModel {
  /// Cost of any object, however small: the fixed per-draw overhead, in triangle-equivalents.
  double a = 100.0;
  /// Cost per triangle.
  double b = 1.0;
  /// Cost per projected pixel (0: no pixel term).
  double c = 0.0;
  /// The screen the pixel term assumes (only used when c > 0).
  int screen_width = 1024, screen_height = 768;
  double fov_degrees = 90.0;  ///< horizontal field of view

  /// The largest a, b or c: every cost sum stays finite.
  static constexpr double kMaxFactor = 1e12;

  bool pixel_term() const { return c > 0; }
  /// Throws Error for negative, non-finite, larger than kMaxFactor or otherwise unusable parameters.
  void validate() const;
  /// One line saying whether the pixel term is computed, and with which screen.
  std::string describe_pixel_term() const;
};

/// The part of r(o) that does not depend on the viewpoint, max(a, b * t_o), per object
/// (0 for objects that are not rendered: they occlude but cost nothing).
std::vector<double> per_object_costs(const Scene& scene, const CostModel& model);

/// Estimated pixels covered by `object` seen from `eye` when the viewer looks at it: its
/// mean projected area (surface area / 4, exact for convex bodies) over the squared distance
/// to its bounding box, times the screen's pixels per steradian; at most the whole screen
/// (also when the eye is inside the bounding box).
double projected_pixels(const ObjectInfo& object, const Vec3& eye, const CostModel& model);

/// The points the pixel term of a cell is estimated from: the centres of the 8 octants of the
/// cell's bounding box.
std::vector<Vec3> pixel_estimation_points(const Box3& cell_bounds);

/// r(o) for a cell: max(base, c * mean over `points` of projected_pixels). `base` is the
/// object's per_object_costs entry. Without the pixel term, returns base.
double cell_object_cost(const ObjectInfo& object, double base, const std::vector<Vec3>& points,
                        const CostModel& model);

/// r(PVS) of a cell with bounding box `bounds` whose PVS is `pvs` (object ids): the sum of
/// cell_object_cost over its objects, or of `base` alone without the pixel term.
double pvs_cost(const Scene& scene, const std::vector<double>& base, const CostModel& model,
                const std::vector<uint32_t>& pvs, const Box3& bounds);

/// True when every cost is a whole number in [0, 2^32) and all of them sum below 2^53 (the
/// default model's max(100, triangles) on any real scene): then every sum of them is exact in
/// a double, whatever the order of the additions.
bool whole_and_small(const std::vector<double>& costs);

/// pvs_cost without the pixel term, for whole_and_small costs: the sum in whole numbers, which
/// is the same value as the sum in order (both are exact) without a chain of dependent
/// floating-point adds (the validated merge sums tens of thousands of lists per candidate).
template <class Id>
double whole_pvs_cost(const std::vector<double>& base, const std::vector<Id>& pvs) {
  uint64_t c = 0;
  for (Id o : pvs) c += static_cast<uint64_t>(base[o]);
  return static_cast<double>(c);
}

/// The union of two sorted id lists, sorted.
std::vector<uint32_t> unite_sorted(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b);
std::vector<uint16_t> unite_sorted(const std::vector<uint16_t>& a, const std::vector<uint16_t>& b);

}  // namespace viewcells
