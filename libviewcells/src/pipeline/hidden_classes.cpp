/// The bake's three answers per (view cell, object) pair and the conservative mode
/// (pipeline/hidden_classes.h; issue 65).
#include "pipeline/hidden_classes.h"

#include <algorithm>

#include "viewcells/core/format.h"
#include "viewcells/scene/cost_model.h"

namespace viewcells::pipeline {

namespace {

Polytope polytope_of(const ConvexPolyhedron& p) {
  Polytope out;
  for (const PolyFace& f : p.faces()) {
    Winding w;
    for (uint32_t v : f.vertices) w.push_back(p.vertices()[v]);
    out.faces.push_back(std::move(w));
  }
  return out;
}

}  // namespace

BakeResult::HiddenClasses prove_hidden_classes(const BakeConfig& c, const LoadedScene& loaded,
                                               const HiddenSpace& space, const Subdivision& bsp,
                                               const std::vector<int32_t>& leaf_cell,
                                               const std::optional<CameraSet>& cams,
                                               std::vector<std::vector<uint32_t>>& lists, const Log& log) {
  BakeResult::HiddenClasses h;
  h.proved = true;
  h.method = space.describe();
  h.warnings = space.warnings();
  for (const std::string& w : h.warnings) log("viewcells: bake: " + w);
  const size_t n = lists.size();
  // Each cell as the convex parts of its BSP leaves, over the box the file covers.
  std::vector<std::vector<Polytope>> cells(n);
  std::vector<double> volume(n, 0);
  clip_to_leaves(bsp, ConvexPolyhedron::box(bsp.view_box, 0), [&](int32_t leaf, const ConvexPolyhedron& part) {
    const int32_t cell = leaf_cell[static_cast<size_t>(leaf)];
    if (cell < 0 || static_cast<size_t>(cell) >= n) return;
    cells[static_cast<size_t>(cell)].push_back(polytope_of(part));
    volume[static_cast<size_t>(cell)] += part.volume();
  });
  const HiddenProof proof = space.prove(cells, c.hidden_max_steps);
  h.floods = proof.floods;
  h.steps = proof.steps;
  h.overflows = proof.overflows;
  h.seconds = proof.seconds;
  const Scene& scene = *loaded.scene;
  const std::vector<double> r = per_object_costs(scene, c.model);
  std::vector<double> weight(n, 0);
  if (cams && !cams->cameras.empty()) {
    for (int32_t cell : cams->cells)
      if (cell >= 0 && static_cast<size_t>(cell) < n) weight[static_cast<size_t>(cell)] += 1;
    h.weights = "frames of the " + std::to_string(cams->cameras.size()) + " measuring cameras per cell";
  } else {
    weight = volume;
    h.weights = "the cells' volumes";
  }
  uint64_t rendered = 0;
  for (const ObjectInfo& info : scene.objects) rendered += info.rendered && info.triangle_count ? 1 : 0;
  double total = 0, visible_cost = 0, conservative_cost = 0;
  for (size_t i = 0; i < n; ++i) {
    std::vector<uint32_t>& seen = lists[i];
    const std::vector<uint32_t>& open = proof.unhidden[i];
    std::vector<uint32_t> undecided;
    std::set_difference(open.begin(), open.end(), seen.begin(), seen.end(), std::back_inserter(undecided));
    double rv = 0, ru = 0;
    uint64_t seen_rendered = 0;
    for (uint32_t o : seen)
      if (scene.objects[o].rendered) {
        rv += r[o];
        ++seen_rendered;
        if (!std::binary_search(open.begin(), open.end(), o)) ++h.conflicts;
      }
    uint64_t undecided_rendered = 0;
    for (uint32_t o : undecided)
      if (scene.objects[o].rendered) {
        ru += r[o];
        ++undecided_rendered;
      }
    h.visible += seen_rendered;
    h.undecided += undecided_rendered;
    h.hidden += rendered - seen_rendered - undecided_rendered;
    total += weight[i];
    visible_cost += weight[i] * rv;
    conservative_cost += weight[i] * (rv + ru);
    if (c.conservative) {
      std::vector<uint32_t> both;
      for (uint32_t o : undecided)
        if (scene.objects[o].rendered) both.push_back(o);
      both.insert(both.end(), seen.begin(), seen.end());
      std::sort(both.begin(), both.end());
      seen = std::move(both);
    }
  }
  h.cost_visible = total > 0 ? visible_cost / total : 0;
  h.cost_conservative = total > 0 ? conservative_cost / total : 0;
  log("viewcells: bake: " + h.method + ": " + std::to_string(h.visible) + " (cell, object) pairs proven visible, " +
      std::to_string(h.hidden) + " proven hidden, " + std::to_string(h.undecided) + " undecided" +
      (h.conflicts ? " (" + std::to_string(h.conflicts) + " seen by rays but proven hidden: cracks or leaks)" : std::string()) +
      "; cost per frame " + fmt(h.cost_visible, 0) + " proven visible, " + fmt(h.cost_conservative, 0) +
      " with the undecided (" + h.weights + "); " + std::to_string(h.floods) + " floods, " + std::to_string(h.steps) +
      " portal steps" + (h.overflows ? ", " + std::to_string(h.overflows) + " over budget" : std::string()) + " in " +
      fmt(h.seconds, 1) + " s" + (c.conservative ? "; the undecided pairs are shipped (--conservative)" : ""));
  return h;
}

}  // namespace viewcells::pipeline
