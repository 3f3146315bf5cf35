/// The render-cost model r(o) = max(a, b t_o, c p_o) and c(S) (view-cell-construction paper,
/// section 3.3).
#include "viewcells/scene/cost_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "viewcells/core/error.h"
#include "viewcells/core/format.h"

namespace viewcells {

void CostModel::validate() const {
  // Costs are sums over objects, cells and viewpoints: a bound on each factor keeps every sum
  // finite (1e12 x 2^32 triangles x 2^32 objects is far inside double's range).
  for (const auto& [name, v] : {std::pair{"a", a}, std::pair{"b", b}, std::pair{"c", c}})
    if (!(v >= 0) || !(v <= kMaxFactor))
      throw Error(std::string("cost model: ") + name + " must be a number from 0 to 1e12 (got " + fmt(v, 3) + ")");
  if (!pixel_term()) return;
  if (screen_width < 1 || screen_height < 1 || screen_width > 65536 || screen_height > 65536)
    throw Error("cost model: the screen must be between 1x1 and 65536x65536 pixels");
  if (!(fov_degrees > 0 && fov_degrees < 180))
    throw Error("cost model: the field of view must lie strictly between 0 and 180 degrees");
}

std::string CostModel::describe_pixel_term() const {
  if (!pixel_term()) return "disabled: c = 0, so r(o) = max(a, b * triangles) and no pixels are estimated";
  return "enabled: c > 0; pixels estimated from the octant centres of each cell's bounding box on a " +
         std::to_string(screen_width) + "x" + std::to_string(screen_height) + " screen with a " +
         std::to_string(static_cast<int>(std::lround(fov_degrees))) + " degree horizontal field of view";
}

std::vector<double> per_object_costs(const Scene& scene, const CostModel& model) {
  model.validate();
  std::vector<double> r(scene.objects.size());
  for (size_t o = 0; o < r.size(); ++o)
    r[o] = scene.objects[o].rendered
               ? std::max(model.a, model.b * static_cast<double>(scene.objects[o].triangle_count))
               : 0.0;
  return r;
}

double projected_pixels(const ObjectInfo& object, const Vec3& eye, const CostModel& model) {
  const double screen = static_cast<double>(model.screen_width) * model.screen_height;
  // Squared distance from the eye to the bounding box (0 inside).
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({object.bounds.lo[k] - eye[k], 0.0, eye[k] - object.bounds.hi[k]});
    d2 += d * d;
  }
  if (!(d2 > 0)) return screen;
  // Pixels per steradian at the centre of the view: the focal length in pixels, squared.
  const double f = 0.5 * model.screen_width / std::tan(0.5 * model.fov_degrees * std::numbers::pi / 180.0);
  const double steradians = 0.25 * object.surface_area / d2;
  return std::min(screen, steradians * f * f);
}

std::vector<Vec3> pixel_estimation_points(const Box3& b) {
  std::vector<Vec3> points;
  points.reserve(8);
  const Vec3 e = b.extent();
  for (int k = 0; k < 8; ++k)
    points.push_back({b.lo.x + e.x * (k & 1 ? 0.75 : 0.25), b.lo.y + e.y * (k & 2 ? 0.75 : 0.25),
                      b.lo.z + e.z * (k & 4 ? 0.75 : 0.25)});
  return points;
}

double cell_object_cost(const ObjectInfo& object, double base, const std::vector<Vec3>& points,
                        const CostModel& model) {
  if (!model.pixel_term() || points.empty() || !object.rendered) return base;
  double sum = 0;
  for (const Vec3& p : points) sum += projected_pixels(object, p, model);
  return std::max(base, model.c * sum / static_cast<double>(points.size()));
}

double pvs_cost(const Scene& scene, const std::vector<double>& base, const CostModel& model,
                const std::vector<uint32_t>& pvs, const Box3& bounds) {
  double c = 0;
  if (!model.pixel_term()) {
    for (uint32_t o : pvs) c += base[o];
    return c;
  }
  const std::vector<Vec3> points = pixel_estimation_points(bounds);
  for (uint32_t o : pvs) c += cell_object_cost(scene.objects[o], base[o], points, model);
  return c;
}

bool whole_and_small(const std::vector<double>& costs) {
  double total = 0;
  for (double x : costs) {
    if (!(x >= 0) || x != std::floor(x) || x >= 0x1p32) return false;
    total += x;
  }
  return total < 0x1p53;
}

namespace {

template <class Id>
std::vector<Id> unite_lists(const std::vector<Id>& a, const std::vector<Id>& b) {
  // Without branches on the comparisons (which a union of similar lists mispredicts half the
  // time), into scratch space of this thread; then copied into a vector of exactly its size.
  thread_local std::vector<Id> scratch;
  if (scratch.size() < a.size() + b.size()) scratch.resize(a.size() + b.size());
  const Id *pa = a.data(), *pb = b.data();
  const size_t na = a.size(), nb = b.size();
  Id* out = scratch.data();
  size_t i = 0, j = 0;
  while (i < na && j < nb) {
    const Id x = pa[i], y = pb[j];
    *out++ = x < y ? x : y;
    i += x <= y;
    j += y <= x;
  }
  out = std::copy(pa + i, pa + na, out);
  out = std::copy(pb + j, pb + nb, out);
  return std::vector<Id>(scratch.data(), out);
}

}  // namespace

std::vector<uint32_t> unite_sorted(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  return unite_lists(a, b);
}

std::vector<uint16_t> unite_sorted(const std::vector<uint16_t>& a, const std::vector<uint16_t>& b) {
  return unite_lists(a, b);
}

}  // namespace viewcells
