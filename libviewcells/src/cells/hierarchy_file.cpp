/// The built hierarchy on disk (.vcells): planes, nodes, split order, leaf PVSs and the merge
/// history.
#include "viewcells/cells/hierarchy_file.h"

#include <algorithm>
#include <cmath>

#include "viewcells/bsp/bsp_io.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"

namespace viewcells {

namespace {
constexpr char kMagic[5] = "VCEL";
// 1: first layout; 2: adds the pixel term's screen (width, height, field of view) after c;
// 3: adds the merge history and the object names at the end.
constexpr uint32_t kVersion = 3;

void put_history(ByteWriter& w, const std::optional<MergeHistory>& h) {
  w.put<uint8_t>(h ? 1 : 0);
  if (!h) return;
  w.put<uint32_t>(h->leaf_count);
  w.put<uint64_t>(h->nodes.size());
  for (const MergeNode& n : h->nodes) {
    w.put<int32_t>(n.child[0]);
    w.put<int32_t>(n.child[1]);
    w.put<int32_t>(n.parent);
    w.put(n.weight);
    w.put(n.volume);
    w.put(n.bounds.lo);
    w.put(n.bounds.hi);
    w.put(n.pvs_cost);
    w.put<uint32_t>(n.pvs_size);
  }
  w.put(h->initial_cost);
  w.put(h->total_weight);
  for (double c : h->cost_after) w.put(c);
}

/// Reads and checks the merge history against the subdivision's leaves and their PVSs.
std::optional<MergeHistory> get_history(ByteReader& r, const Subdivision& s,
                                        const std::vector<std::vector<uint32_t>>& leaf_pvs, uint64_t max_items) {
  if (r.get<uint8_t>() == 0) return std::nullopt;
  MergeHistory h;
  h.leaf_count = r.get<uint32_t>();
  const std::vector<int32_t> leaves = s.leaves();
  if (h.leaf_count != leaves.size()) r.fail("the merge history does not match the subdivision's leaves");
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes < h.leaf_count || nodes > 2ull * h.leaf_count - 1 || nodes > max_items) r.fail("invalid merge node count");
  h.nodes.resize(nodes);
  for (MergeNode& n : h.nodes) {
    n.child[0] = r.get<int32_t>();
    n.child[1] = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.weight = r.get<double>();
    n.volume = r.get<double>();
    n.bounds.lo = r.get<Vec3>();
    n.bounds.hi = r.get<Vec3>();
    n.pvs_cost = r.get<double>();
    n.pvs_size = r.get<uint32_t>();
    if (!(n.weight >= 0) || !(n.volume > 0) || !(n.pvs_cost >= 0) || !std::isfinite(n.pvs_cost) ||
        !is_finite(n.bounds.lo) || !is_finite(n.bounds.hi))
      r.fail("invalid merge node");
  }
  h.initial_cost = r.get<double>();
  h.total_weight = r.get<double>();
  h.cost_after.resize(nodes - h.leaf_count);
  for (double& c : h.cost_after) {
    c = r.get<double>();
    if (!std::isfinite(c)) r.fail("invalid cost in the merge history");
  }
  // Structure: leaves first; merge k is node L + k, made of two earlier nodes.
  const int32_t L = static_cast<int32_t>(h.leaf_count);
  for (int32_t i = 0; i < static_cast<int32_t>(nodes); ++i) {
    const MergeNode& n = h.nodes[i];
    const bool leaf = i < L;
    if (leaf != (n.child[0] < 0) || leaf != (n.child[1] < 0)) r.fail("merge node " + std::to_string(i) + " is malformed");
    if (n.parent != -1 && (n.parent <= i || n.parent >= static_cast<int32_t>(nodes) ||
                           (h.nodes[n.parent].child[0] != i && h.nodes[n.parent].child[1] != i)))
      r.fail("merge node " + std::to_string(i) + " has a wrong parent");
    if (!leaf)
      for (int32_t c : n.child)
        if (c >= i || h.nodes[c].parent != i) r.fail("merge node " + std::to_string(i) + " has a wrong child");
    if (leaf && n.pvs_size != leaf_pvs[leaves[i]].size()) r.fail("merge leaf " + std::to_string(i) + " has another PVS");
  }
  return h;
}

}  // namespace

void write_subdivision(const std::string& path, const SubdivisionFile& f) {
  const Subdivision& s = f.subdivision;
  ByteWriter w;
  // The payload's size, about (the leaves' lists are most of it), reserved at once.
  size_t bytes = 4096 + 64 * s.planes.size() + 40 * s.nodes.size() + 20 * s.splits.size();
  for (const std::vector<uint32_t>& l : f.leaf_pvs) bytes += 8 + 4 * l.size();
  if (f.history) bytes += 96 * f.history->nodes.size();
  for (const std::string& n : f.object_names) bytes += 8 + n.size();
  w.reserve(bytes);
  w.put(s.view_box.lo);
  w.put(s.view_box.hi);
  w.put(f.cost_model.a);
  w.put(f.cost_model.b);
  w.put(f.cost_model.c);
  w.put<int32_t>(f.cost_model.screen_width);
  w.put<int32_t>(f.cost_model.screen_height);
  w.put(f.cost_model.fov_degrees);
  w.put<uint64_t>(f.scene_fingerprint);
  w.put<uint32_t>(f.object_count);
  w.put(s.initial_cost);
  put_planes(w, s.planes);
  w.put<uint64_t>(s.nodes.size());
  for (const BspNode& n : s.nodes) {
    w.put<int32_t>(n.plane);
    w.put<int32_t>(n.child[0]);
    w.put<int32_t>(n.child[1]);
    w.put<int32_t>(n.parent);
    w.put(n.volume);
    w.put(n.weight);
    w.put(n.pvs_cost);
  }
  w.put<uint64_t>(s.splits.size());
  for (const SplitRecord& r : s.splits) {
    w.put<int32_t>(r.node);
    w.put(r.reduction);
    w.put(r.cost_after);
  }
  for (size_t n = 0; n < s.nodes.size(); ++n) w.put_array(n < f.leaf_pvs.size() ? f.leaf_pvs[n] : std::vector<uint32_t>{});
  put_history(w, f.history);
  if (!f.object_names.empty() && f.object_names.size() != f.object_count)
    throw Error(path, 0, "object names do not match the object count");
  w.put<uint64_t>(f.object_names.size());
  for (const std::string& n : f.object_names) w.put_string(n);
  write_container(path, kMagic, kVersion, w.data());
}

SubdivisionFile read_subdivision(const std::string& path) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kMagic, kVersion, version);
  ByteReader r(payload, path);
  SubdivisionFile f;
  Subdivision& s = f.subdivision;
  s.view_box = get_view_box(r);
  f.cost_model.a = r.get<double>();
  f.cost_model.b = r.get<double>();
  f.cost_model.c = r.get<double>();
  if (version >= 2) {
    f.cost_model.screen_width = r.get<int32_t>();
    f.cost_model.screen_height = r.get<int32_t>();
    f.cost_model.fov_degrees = r.get<double>();
  }
  try {
    f.cost_model.validate();
  } catch (const Error& e) {
    r.fail(std::string("invalid cost model (") + e.what() + ")");
  }
  f.scene_fingerprint = r.get<uint64_t>();
  f.object_count = r.get<uint32_t>();
  s.initial_cost = r.get<double>();
  const uint64_t max_items = payload.size() / 8;
  s.planes = get_planes(r, max_items);
  const uint64_t planes = s.planes.size();
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes == 0 || nodes > max_items || nodes % 2 == 0) r.fail("invalid node count");
  s.nodes.resize(nodes);
  for (BspNode& n : s.nodes) {
    n.plane = r.get<int32_t>();
    n.child[0] = r.get<int32_t>();
    n.child[1] = r.get<int32_t>();
    n.parent = r.get<int32_t>();
    n.volume = r.get<double>();
    n.weight = r.get<double>();
    n.pvs_cost = r.get<double>();
  }
  const uint64_t splits = r.get<uint64_t>();
  if (splits > max_items || 2 * splits + 1 != nodes) r.fail("split count does not match the node count");
  s.splits.resize(splits);
  for (SplitRecord& rec : s.splits) {
    rec.node = r.get<int32_t>();
    rec.reduction = r.get<double>();
    rec.cost_after = r.get<double>();
  }
  f.leaf_pvs.resize(nodes);
  for (auto& pvs : f.leaf_pvs) r.get_array(pvs, max_items);
  const size_t history_at = r.position();
  // Structure: split k splits an existing leaf into nodes 2k+1 and 2k+2 on plane 6 + k.
  const int32_t n_nodes = static_cast<int32_t>(nodes);
  if (s.nodes[0].parent != -1) r.fail("the root has a parent");
  for (size_t k = 0; k < splits; ++k) {
    const int32_t node = s.splits[k].node;
    if (node < 0 || node > static_cast<int32_t>(2 * k)) r.fail("split " + std::to_string(k) + " names a node not yet created");
    const BspNode& n = s.nodes[node];
    const int32_t c0 = static_cast<int32_t>(2 * k + 1), c1 = c0 + 1;
    if (n.plane != static_cast<int32_t>(6 + k) || n.child[0] != c0 || n.child[1] != c1 || s.nodes[c0].parent != node ||
        s.nodes[c1].parent != node)
      r.fail("split " + std::to_string(k) + " does not match the tree");
  }
  for (int32_t i = 0; i < n_nodes; ++i) {
    const BspNode& n = s.nodes[i];
    if (n.plane >= static_cast<int32_t>(planes) || !(n.volume > 0) || !(n.weight >= 0) || !(n.pvs_cost >= 0))
      r.fail("node " + std::to_string(i) + " is invalid");
    if (n.plane < 0 && (n.child[0] != -1 || n.child[1] != -1)) r.fail("leaf " + std::to_string(i) + " has children");
    for (uint32_t o : f.leaf_pvs[i])
      if (o >= f.object_count) r.fail("node " + std::to_string(i) + " lists object " + std::to_string(o));
    if (!std::is_sorted(f.leaf_pvs[i].begin(), f.leaf_pvs[i].end())) r.fail("unsorted PVS");
  }
  if (planes != 6 + splits) r.fail("plane count does not match the split count");
  if (!(s.nodes[0].weight > 0)) r.fail("the view space has zero weight");
  if (version >= 3) {
    r.seek(history_at);
    f.history = get_history(r, s, f.leaf_pvs, max_items);
    const uint64_t names = r.get<uint64_t>();
    if (names != 0 && names != f.object_count) r.fail("object names do not match the object count");
    for (uint64_t i = 0; i < names; ++i) f.object_names.push_back(r.get_string());
  }
  if (!r.at_end()) r.fail("trailing bytes");
  return f;
}

}  // namespace viewcells
