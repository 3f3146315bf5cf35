// AGVS paper 6: dynamic updates: objects matched across an edit, deleted ones removed, and
// what inserted ones may hide (their penumbrae) removed before sampling resumes.
#include "solver_impl.h"

#include <tbb/parallel_for.h>

#include <map>

#include "viewcells/agvs/penumbra.h"

namespace viewcells {

std::vector<uint32_t> match_objects(const Scene& before, const Scene& after) {
  // Per object: its name and a hash of its triangles' corner coordinates, in order.
  auto keys = [](const Scene& s) {
    std::vector<ByteWriter> geometry(s.object_count());
    for (uint32_t t = 0; t < s.triangles.size(); ++t)
      for (uint32_t v : s.triangles[t]) geometry[s.triangle_object[t]].put(s.vertices[v]);
    std::vector<std::pair<std::string, uint64_t>> out;
    for (uint32_t o = 0; o < s.object_count(); ++o) out.emplace_back(s.objects[o].name, fnv1a64(geometry[o].data()));
    return out;
  };
  std::multimap<std::pair<std::string, uint64_t>, uint32_t> free;
  const auto after_keys = keys(after);
  for (uint32_t o = 0; o < after_keys.size(); ++o) free.emplace(after_keys[o], o);
  std::vector<uint32_t> new_of_old;
  for (const auto& key : keys(before)) {
    const auto it = free.find(key);  // the first among equals: multimap keeps insertion order
    if (it == free.end()) {
      new_of_old.push_back(kNoObject);
    } else {
      new_of_old.push_back(it->second);
      free.erase(it);
    }
  }
  return new_of_old;
}

AgvsEditStats AgvsSolver::Impl::edit(const Scene& edited, const RayCaster& rc, const std::vector<uint32_t>& new_of_old) {
  const uint32_t old_n = pvs.object_count(), new_n = static_cast<uint32_t>(edited.object_count());
  if (new_of_old.size() != old_n)
    throw Error("the edit maps " + std::to_string(new_of_old.size()) + " objects, the solution has " +
                std::to_string(old_n));
  AgvsEditStats st;
  std::vector<char> kept(new_n, 0);
  for (uint32_t m : new_of_old) {
    if (m == kNoObject) {
      ++st.deleted;
      continue;
    }
    if (m >= new_n || kept[m]) throw Error("the edit's object map is not one-to-one");
    kept[m] = 1;
  }
  std::vector<uint32_t> inserted;
  for (uint32_t o = 0; o < new_n; ++o)
    if (!kept[o]) inserted.push_back(o);
  st.inserted = static_cast<uint32_t>(inserted.size());
  // The solution over the new objects, without the deleted ones.
  GlobalPvs next(cells.cell_count(), new_n);
  std::vector<uint16_t> next_hits;
  if (config.filter_statistics) next_hits.assign(size_t(cells.cell_count()) * new_n, 0);
  for (uint32_t c = 0; c < cells.cell_count(); ++c) {
    for (uint32_t o : pvs.list(c)) {
      if (new_of_old[o] == kNoObject) ++st.removed_deleted;
      else next.insert(c, new_of_old[o]);
    }
    if (config.filter_statistics)
      for (uint32_t o = 0; o < old_n; ++o)
        if (new_of_old[o] != kNoObject)
          next_hits[size_t(c) * new_n + new_of_old[o]] = hit_counts[size_t(c) * old_n + o];
  }
  // Inserted objects: what they may hide from each cell leaves its PVS.
  const Scene& sc = edited;
  Box3 all = sc.bounds;
  all.extend(cells.view_box());
  const double reach = all.diagonal();
  std::vector<std::vector<Vec3>> vertices_of(new_n);
  for (uint32_t t = 0; t < sc.triangles.size(); ++t)
    if (!kept[sc.triangle_object[t]])
      for (uint32_t v : sc.triangles[t]) vertices_of[sc.triangle_object[t]].push_back(sc.vertices[v]);
  for (uint32_t o : inserted) {
    if (vertices_of[o].empty() || !sc.objects[o].occluder) continue;  // hides nothing
    const std::vector<Vec3> hull = convex_hull_vertices(vertices_of[o]);
    std::vector<std::vector<uint32_t>> removed(cells.cell_count());
    std::vector<char> cleared(cells.cell_count(), 0);
    tbb::parallel_for(uint32_t{0}, cells.cell_count(), [&](uint32_t c) {
      const ConvexRegion shadow = penumbra(hull, cells.cell_bounds(c), reach);
      cleared[c] = shadow.is_everything();
      for (uint32_t e : next.list(c))
        if (shadow.may_intersect(sc.objects[e].bounds)) removed[c].push_back(e);
    });
    for (uint32_t c = 0; c < cells.cell_count(); ++c) {
      st.cells_cleared += cleared[c];
      for (uint32_t e : removed[c]) st.removed_penumbra += next.erase(c, e);
    }
  }
  // Everything is computed: commit (bind changes nothing when it throws).
  bind(edited, rc);
  pvs = std::move(next);
  hit_counts = std::move(next_hits);
  // Mutation candidates keep their segments; their objects follow the map.
  for (MutationLane& lane : lanes)
    for (CandidateBuffer* b : {&lane.two_point, &lane.silhouette})
      b->for_each([&](Candidate& cand) {
        if (cand.object != kNoObject) cand.object = new_of_old[cand.object];
      });
  // The estimator's rays described the old scene.
  window.clear();
  window_total = 0;
  evaluate_window();
  return st;
}

AgvsEditStats AgvsSolver::edit(const Scene& edited, const RayCaster& caster, const std::vector<uint32_t>& new_of_old) {
  return impl_->edit(edited, caster, new_of_old);
}

}  // namespace viewcells
