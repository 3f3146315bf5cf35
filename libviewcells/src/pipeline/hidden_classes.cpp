/// The bake's three answers per (view cell, object) pair and the conservative mode
/// (pipeline/hidden_classes.h; issue 65).
#include "pipeline/hidden_classes.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <iterator>

#include "viewcells/core/format.h"
#include "viewcells/core/interrupt.h"
#include "viewcells/core/progress.h"
#include "viewcells/core/rng.h"
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

CellProof prove_cells(const BakeConfig& c, const HiddenSpace& space, const Subdivision& bsp,
                      const std::vector<int32_t>& leaf_cell, size_t cell_count, const Deadline& deadline) {
  // Each cell as the convex parts of its BSP leaves, over the box the file covers.
  std::vector<std::vector<Polytope>> cells(cell_count);
  CellProof out;
  out.volume.assign(cell_count, 0);
  clip_to_leaves(bsp, ConvexPolyhedron::box(bsp.view_box, 0), [&](int32_t leaf, const ConvexPolyhedron& part) {
    const int32_t cell = leaf_cell[static_cast<size_t>(leaf)];
    if (cell < 0 || static_cast<size_t>(cell) >= cell_count) return;
    cells[static_cast<size_t>(cell)].push_back(polytope_of(part));
    out.volume[static_cast<size_t>(cell)] += part.volume();
  });
  out.proof = space.prove(cells, c.hidden_max_steps, deadline);
  return out;
}

AimedRays aim_at_undecided(const BakeConfig& c, const LoadedScene& loaded, const HiddenSpace& space,
                           const CellProof& proved, const CellLocator& cells,
                           std::vector<std::vector<uint32_t>>& lists, const Deadline& deadline, const Log& log) {
  Stopwatch sw;
  const Scene& scene = *loaded.scene;
  // Per object, its triangles and their running areas: a point uniform on its surface.
  std::vector<std::vector<uint32_t>> tris(scene.object_count());
  std::vector<std::vector<double>> area(scene.object_count());
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    const uint32_t o = scene.triangle_object[t];
    tris[o].push_back(t);
    area[o].push_back((area[o].empty() ? 0.0 : area[o].back()) + 0.5 * length(scene.triangle_normal(t)));
  }
  auto on_surface = [&](uint32_t o, Rng& rng) {
    const std::vector<double>& a = area[o];
    const size_t i = std::min<size_t>(std::upper_bound(a.begin(), a.end(), rng.uniform() * a.back()) - a.begin(),
                                      a.size() - 1);
    const auto& tri = scene.triangles[tris[o][i]];
    double u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const Vec3& p0 = scene.vertices[tri[0]];
    return p0 + (scene.vertices[tri[1]] - p0) * u + (scene.vertices[tri[2]] - p0) * v;
  };
  const size_t n = lists.size();
  std::vector<std::vector<uint32_t>> found(n);
  std::vector<uint64_t> pairs(n, 0), rays(n, 0);
  Progress progress("aimed rays", n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<Ray> batch;
    std::vector<Hit> hits;
    std::vector<uint32_t> owner, open, still;
    std::vector<Vec3> eyes;
    for (size_t cell = r.begin(); cell < r.end(); ++cell) {
      throw_if_interrupted("aimed rays");
      progress.advance();
      if (deadline.passed()) continue;
      const std::vector<uint32_t>& unhidden = proved.proof.unhidden[cell];
      open.clear();
      for (uint32_t o : unhidden)
        if (scene.objects[o].rendered && !tris[o].empty() && !std::binary_search(lists[cell].begin(), lists[cell].end(), o))
          open.push_back(o);
      pairs[cell] = open.size();
      if (open.empty()) continue;
      Rng rng(c.agvs.seed ^ 0x41'4d'45'44ULL, cell);
      // Viewpoints: uniform in the cell's box, kept where the cell is and space is empty.
      const Box3& b = cells.cell_bounds(static_cast<uint32_t>(cell));
      eyes.clear();
      for (uint32_t tries = 0; eyes.size() < 1024 && tries < 1024 * 32; ++tries) {
        const Vec3 p{rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y), rng.uniform(b.lo.z, b.hi.z)};
        if (cells.cell_at(p) == static_cast<int32_t>(cell) && !space.solid_at(p)) eyes.push_back(p);
      }
      if (eyes.empty()) continue;
      uint32_t sent = 0;
      std::vector<uint8_t> seen;
      for (uint32_t round = 8; !open.empty() && sent < c.aimed_rays; round *= 2) {
        const uint32_t k = std::min(round, c.aimed_rays - sent);
        sent += k;
        seen.assign(open.size(), 0);
        // In batches of at most about 2^20 rays, whatever the round's size.
        const size_t per_batch = std::max<size_t>(1, (size_t{1} << 20) / k);
        for (size_t first = 0; first < open.size(); first += per_batch) {
          const size_t last = std::min(open.size(), first + per_batch);
          batch.clear();
          owner.clear();
          for (size_t i = first; i < last; ++i)
            for (uint32_t j = 0; j < k; ++j) {
              const Vec3 eye = eyes[rng.below(eyes.size())];
              const Vec3 d = on_surface(open[i], rng) - eye;
              const double len = length(d);
              if (!(len > 0)) continue;
              batch.push_back(Ray{eye, d * (1 / len), 0, len * (1 + 1e-6)});
              owner.push_back(static_cast<uint32_t>(i));
            }
          hits.resize(batch.size());
          loaded.caster->intersect(batch, hits);
          rays[cell] += batch.size();
          for (size_t j = 0; j < batch.size(); ++j) {
            const uint32_t o = open[owner[j]];
            // An occluder is seen when it is what the ray meets first; a see-through object
            // (never met: the caster skips it) when nothing is met before its point.
            const bool reached = scene.objects[o].occluder
                                     ? hits[j].hit() && hits[j].object == o
                                     : !hits[j].hit() || hits[j].t >= batch[j].tfar / (1 + 1e-6) * (1 - 1e-6);
            if (reached) seen[owner[j]] = 1;
          }
        }
        still.clear();
        for (uint32_t i = 0; i < open.size(); ++i) (seen[i] ? found[cell] : still).push_back(open[i]);
        open.swap(still);
      }
    }
  });
  progress.finish();
  AimedRays out;
  std::vector<uint32_t> merged;
  for (size_t cell = 0; cell < n; ++cell) {
    out.pairs += pairs[cell];
    out.rays += rays[cell];
    out.found += found[cell].size();
    if (found[cell].empty()) continue;
    std::sort(found[cell].begin(), found[cell].end());
    merged.clear();
    std::set_union(lists[cell].begin(), lists[cell].end(), found[cell].begin(), found[cell].end(),
                   std::back_inserter(merged));
    lists[cell].swap(merged);
  }
  out.seconds = sw.seconds();
  log("viewcells: bake: aimed rays: " + std::to_string(out.rays) + " rays at " + std::to_string(out.pairs) +
      " undecided (cell, object) pairs proved " + std::to_string(out.found) + " of them visible in " +
      fmt(out.seconds, 1) + " s" + (deadline.passed() ? " (the time limit stopped them)" : ""));
  return out;
}

BakeResult::HiddenClasses hidden_classes(const BakeConfig& c, const LoadedScene& loaded, const HiddenSpace& space,
                                         const CellProof& proved, const AimedRays& aimed,
                                         const std::optional<CameraSet>& cams,
                                         std::vector<std::vector<uint32_t>>& lists, const Log& log) {
  BakeResult::HiddenClasses h;
  h.proved = true;
  h.method = space.describe();
  h.warnings = space.warnings();
  for (const std::string& w : h.warnings) log("viewcells: bake: " + w);
  const size_t n = lists.size();
  const HiddenProof& proof = proved.proof;
  VC_CHECK(proof.unhidden.size() == n && proved.volume.size() == n);
  h.floods = proof.floods;
  h.aimed_pairs = aimed.pairs;
  h.aimed_rays = aimed.rays;
  h.aimed_found = aimed.found;
  h.aimed_seconds = aimed.seconds;
  h.steps = proof.steps;
  h.overflows = proof.overflows;
  h.cells_unproven = proof.cells_unproven;
  h.seconds = proof.seconds;
  const Scene& scene = *loaded.scene;
  const std::vector<double> r = per_object_costs(scene, c.model);
  std::vector<double> weight(n, 0);
  if (cams && !cams->cameras.empty()) {
    for (int32_t cell : cams->cells)
      if (cell >= 0 && static_cast<size_t>(cell) < n) weight[static_cast<size_t>(cell)] += 1;
    h.weights = "frames of the " + std::to_string(cams->cameras.size()) + " measuring cameras per cell";
  } else {
    weight = proved.volume;
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
      " portal steps" + (h.overflows ? ", " + std::to_string(h.overflows) + " over budget" : std::string()) +
      (h.cells_unproven ? ", " + std::to_string(h.cells_unproven) + " cells not proven: the time limit ran out" : std::string()) +
      " in " +
      fmt(h.seconds, 1) + " s" + (c.conservative ? "; the undecided pairs are shipped (--conservative)" : ""));
  return h;
}

}  // namespace viewcells::pipeline
