// AGVS paper 5: visibility filtering: the object space filter (boxes enlarged by what the
// sampling density leaves unresolved) and the view space filter (similar neighbours).
#include "solver_impl.h"

#include <tbb/parallel_for.h>

#include <iterator>

namespace viewcells {

std::vector<std::vector<uint32_t>> AgvsSolver::Impl::filtered(const VisibilityFilter& f) const {
  const uint32_t n_cells = cells.cell_count(), n_obj = pvs.object_count();
  if (f.object_space && !config.filter_statistics)
    throw Error("the object space filter needs the sampling densities (AgvsConfig::filter_statistics)");
  if (!(f.k >= 0) || !std::isfinite(f.k)) throw Error("the filter factor k must be finite and >= 0");
  const Scene& sc = scene();
  std::vector<std::vector<uint32_t>> out(n_cells);
  std::vector<std::pair<Box3, uint32_t>> boxes;
  for (uint32_t o = 0; o < n_obj; ++o)
    if (sc.objects[o].rendered && sc.objects[o].triangle_count > 0) boxes.emplace_back(sc.objects[o].bounds, o);
  const BoxTree tree(std::move(boxes));
  tbb::parallel_for(uint32_t{0}, n_cells, [&](uint32_t c) {
    std::vector<uint32_t> list = pvs.list(c);
    if (f.object_space) {
      const double n_v = static_cast<double>(cell_samples[c]);
      const Box3& cb = cells.cell_bounds(c);
      std::vector<uint32_t> found;
      for (uint32_t o : list) {
        const Box3& ob = sc.objects[o].bounds;
        const double hits = hit_counts[size_t(c) * n_obj + o];
        const double e_g = n_v > 0 ? 2 * box_distance(cb, ob) / std::sqrt(n_v) : 0.0;
        const double e_l = hits > 0 ? object_radius[o] / std::sqrt(hits) : e_g;
        const double e = f.k * std::min(e_g, e_l);
        tree.query(Box3(ob.lo - Vec3{e, e, e}, ob.hi + Vec3{e, e, e}), found);
      }
      list.insert(list.end(), found.begin(), found.end());
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    out[c] = std::move(list);
  });
  if (f.view_neighbours > 0) {
    // Merge with the most similar neighbours (by the object space result, Jaccard).
    const auto near = cells.neighbours();
    std::vector<std::vector<uint32_t>> merged(n_cells);
    tbb::parallel_for(uint32_t{0}, n_cells, [&](uint32_t c) {
      std::vector<std::pair<double, uint32_t>> ranked;
      for (uint32_t nb : near[c]) {
        std::vector<uint32_t> common;
        std::set_intersection(out[c].begin(), out[c].end(), out[nb].begin(), out[nb].end(), std::back_inserter(common));
        const double uni = static_cast<double>(out[c].size() + out[nb].size() - common.size());
        ranked.emplace_back(uni > 0 ? -static_cast<double>(common.size()) / uni : 0.0, nb);  // most similar first
      }
      std::sort(ranked.begin(), ranked.end());
      std::vector<uint32_t> list = out[c];
      for (size_t k = 0; k < ranked.size() && k < f.view_neighbours; ++k)
        list.insert(list.end(), out[ranked[k].second].begin(), out[ranked[k].second].end());
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      merged[c] = std::move(list);
    });
    out = std::move(merged);
  }
  return out;
}

std::vector<std::vector<uint32_t>> AgvsSolver::filtered_pvs(const VisibilityFilter& filter) const {
  return impl_->filtered(filter);
}

}  // namespace viewcells
