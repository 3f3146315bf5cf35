// The payload of a .pvs file read into a handle (handle.h): the BSP, the general planes, the
// visible sets (expanded, or kept coded for a compact handle), names, and the grid where
// location starts. Every count and index is checked before it is used; nothing in a file can
// make the reader read out of bounds, loop or allocate beyond what the file's own size implies.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "container.h"
#include "handle.h"
#include "viewcells/format/id_lists.h"
#include "viewcells/format/orientation.h"

namespace viewcells::runtime_detail {

namespace {

bool finite(const Vec& p) { return std::isfinite(p.v[0]) && std::isfinite(p.v[1]) && std::isfinite(p.v[2]); }

Vec get_vec(Reader& r) {
  Vec p;
  for (double& x : p.v) x = r.get<double>();
  return p;
}

/// Planes and nodes: every inner node has a valid plane and two later children, every node
/// but the root one parent, every leaf a view cell.
void read_bsp(Reader& r, vc_pvs& f, uint64_t max_items) {
  std::vector<int32_t> leaf_cell;
  const uint64_t plane_count = r.get<uint64_t>();
  if (plane_count < 6 || plane_count > max_items) throw FileError("corrupt file: invalid plane count");
  std::vector<int32_t> axis(plane_count), general(plane_count, -1);
  std::vector<double> offset(plane_count);
  for (uint64_t i = 0; i < plane_count; ++i) {
    axis[i] = r.get<int32_t>();
    const Vec normal = get_vec(r);
    offset[i] = r.get<double>();
    GeneralPlane g{get_vec(r), get_vec(r), get_vec(r)};
    if (axis[i] < -1 || axis[i] > 2 || !finite(normal) || !std::isfinite(offset[i]))
      throw FileError("corrupt file: invalid plane");
    if (axis[i] < 0) {
      if (!finite(g.a) || !finite(g.b) || !finite(g.c)) throw FileError("corrupt file: invalid plane");
      general[i] = static_cast<int32_t>(f.planes.size());
      f.planes.push_back(g);
    }
  }
  const uint64_t count = r.get<uint64_t>();
  if (count == 0 || count > max_items || count % 2 == 0 || count >= kIndex)
    throw FileError("corrupt file: invalid node count");
  if (f.planes.size() > kIndex) throw FileError("corrupt file: invalid plane count");
  struct Raw {
    int32_t plane, child[2];
  };
  std::vector<Raw> raw(count);
  leaf_cell.resize(count);
  std::vector<int> parents(count, 0);
  for (uint64_t n = 0; n < count; ++n) {
    Raw& b = raw[n];
    b.plane = r.get<int32_t>();
    b.child[0] = r.get<int32_t>();
    b.child[1] = r.get<int32_t>();
    leaf_cell[n] = r.get<int32_t>();
    if (b.plane < 0) {
      if (b.child[0] != -1 || b.child[1] != -1)
        throw FileError("corrupt file: BSP leaf " + std::to_string(n) + " has children");
      continue;
    }
    if (static_cast<uint64_t>(b.plane) >= plane_count || leaf_cell[n] != -1)
      throw FileError("corrupt file: BSP node " + std::to_string(n) + " is invalid");
    for (int32_t ch : b.child) {
      if (ch <= static_cast<int64_t>(n) || static_cast<uint64_t>(ch) >= count)
        throw FileError("corrupt file: BSP node " + std::to_string(n) + " has a bad child");
      ++parents[ch];
    }
  }
  for (uint64_t n = 1; n < count; ++n)
    if (parents[n] != 1) throw FileError("corrupt file: BSP node " + std::to_string(n) + " is not in the tree once");
  // Preorder layout (a tree, checked above): the negative child right after its parent.
  f.nodes.reserve(count);
  std::vector<std::pair<int32_t, int64_t>> stack = {{0, -1}};  // (file node, parent's slot for `right`)
  while (!stack.empty()) {
    const auto [old, slot] = stack.back();
    stack.pop_back();
    const uint32_t me = static_cast<uint32_t>(f.nodes.size());
    if (slot >= 0) f.nodes[slot].right = me;
    Node node{};
    node.right = 0;
    const Raw& b = raw[old];
    if (b.plane < 0) {
      node.meta = static_cast<uint32_t>(leaf_cell[old]);  // checked against the cell count later
      node.list[0] = node.list[1] = 0;
      f.nodes.push_back(node);
      continue;
    }
    node.offset = offset[b.plane];
    node.meta = axis[b.plane] >= 0 ? static_cast<uint32_t>(axis[b.plane]) << 30
                                   : (3u << 30) | static_cast<uint32_t>(general[b.plane]);
    f.nodes.push_back(node);
    stack.push_back({b.child[1], me});
    stack.push_back({b.child[0], -1});  // popped next: lands at me + 1
  }
}

/// Decodes the kept lists of the hierarchy and checks them; then expands every cell's visible
/// set, or for a compact handle keeps the lists coded (format 2) with where each starts.
void read_lists(Reader& r, vc_pvs& f, uint64_t max_items, uint32_t version) {
  f.cell_count = r.get<uint32_t>();
  const std::vector<int32_t> parent = r.get_array<int32_t>(max_items);
  const std::vector<uint32_t> mht = r.get_array<uint32_t>(max_items);
  const std::string lists = r.get_string();
  if (!r.at_end()) throw FileError("corrupt file: trailing bytes");
  const size_t total = parent.size();
  if (f.cell_count == 0 || f.cell_count > total || mht.size() != f.cell_count)
    throw FileError("corrupt file: invalid view cell count");
  for (size_t n = 0; n < total; ++n)
    if (parent[n] != -1 && (parent[n] <= static_cast<int64_t>(n) || static_cast<size_t>(parent[n]) >= total))
      throw FileError("corrupt file: hierarchy node " + std::to_string(n) + " has a bad parent");
  std::vector<std::vector<uint32_t>> stored(total);
  if (version == 1) {  // LEB128 varints of the differences
    Reader lr(lists);
    for (auto& ids : stored) {
      const uint32_t n = lr.get_varint();
      if (n > f.object_count) throw FileError("corrupt file: a list holds more entries than there are objects");
      ids.resize(n);
      uint64_t previous = 0;
      for (uint32_t i = 0; i < n; ++i) {
        const uint64_t id = (i ? previous + 1 : 0) + lr.get_varint();
        if (id >= f.object_count) throw FileError("corrupt file: object id out of range");
        ids[i] = static_cast<uint32_t>(id);
        previous = id;
      }
    }
    if (!lr.at_end()) throw FileError("corrupt file: trailing bytes after the PVS lists");
  } else {  // binary interpolative coding (id_lists.h)
    if (f.compact && 8 * static_cast<uint64_t>(lists.size()) > std::numeric_limits<uint32_t>::max())
      throw FileError("the coded lists exceed 2^32 bits, more than a compact handle indexes");
    viewcells::id_lists::BitReader lr(lists.data(), lists.size());
    for (size_t n = 0; n < total; ++n) {
      if (f.compact) f.node_bit.push_back(static_cast<uint32_t>(lr.position()));
      if (!viewcells::id_lists::get_list(lr, f.object_count, stored[n]))
        throw FileError("corrupt file: malformed PVS list of hierarchy node " + std::to_string(n));
    }
    if (!lr.at_end()) throw FileError("corrupt file: trailing bytes after the PVS lists");
    if (f.compact) f.coded = lists;
  }
  if (f.compact) {
    // Format 1's lists coded as format 2's; each cell's path checked for repeats one cell at a
    // time; only the coding is kept.
    if (version == 1) {
      viewcells::id_lists::BitWriter w;
      f.node_bit.reserve(total);
      for (const auto& ids : stored) {
        if (w.bits() > std::numeric_limits<uint32_t>::max())
          throw FileError("the coded lists exceed 2^32 bits, more than a compact handle indexes");
        f.node_bit.push_back(static_cast<uint32_t>(w.bits()));
        viewcells::id_lists::put_list(w, ids.data(), ids.size(), f.object_count);
      }
      f.coded = w.finish();
    }
    f.node_parent = parent;
    std::vector<uint32_t> cell;
    for (uint32_t c = 0; c < f.cell_count; ++c) {
      cell.clear();
      for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n]) {
        if (cell.size() + stored[n].size() > f.object_count)
          throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
        cell.insert(cell.end(), stored[n].begin(), stored[n].end());
      }
      std::sort(cell.begin(), cell.end());
      if (std::adjacent_find(cell.begin(), cell.end()) != cell.end())
        throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    }
    return;
  }
  // Size first: a path may not repeat an object, so a cell holds at most object_count.
  uint64_t expanded = 0;
  for (uint32_t c = 0; c < f.cell_count; ++c) {
    uint64_t here = 0;
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n]) here += stored[n].size();
    if (here > f.object_count) throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    expanded += here;
  }
  if (expanded > (uint64_t{1} << 31))
    throw FileError("the expanded visible sets hold " + std::to_string(expanded) + " entries, more than 2^31");
  f.offsets.reserve(f.cell_count + 1);
  f.ids.reserve(expanded);
  f.offsets.push_back(0);
  for (uint32_t c = 0; c < f.cell_count; ++c) {
    const size_t first = f.ids.size();
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = parent[n])
      f.ids.insert(f.ids.end(), stored[n].begin(), stored[n].end());
    std::sort(f.ids.begin() + first, f.ids.end());
    if (std::adjacent_find(f.ids.begin() + first, f.ids.end()) != f.ids.end())
      throw FileError("corrupt file: cell " + std::to_string(c) + " repeats an object");
    f.offsets.push_back(f.ids.size());
  }
}

/// The deepest node whose subtree holds the whole box [lo, hi]: below it, every point of the
/// box takes the same branch at every node (a plane's side is linear in the point, so the
/// corners decide: all on the negative side or on the plane, or all strictly positive).
uint32_t deepest_node(const vc_pvs& f, const double lo[3], const double hi[3]) {
  uint32_t n = 0;
  while (f.nodes[n].right) {
    const Node& node = f.nodes[n];
    const uint32_t axis = node.meta >> 30;
    bool all_neg = true, all_pos = true;
    if (axis < 3) {
      all_neg = hi[axis] <= node.offset;
      all_pos = lo[axis] > node.offset;
    } else {
      // The filter alone: a corner it cannot decide stops the descent (the grid only needs to
      // be right where it descends, and exact signs of a grid of corners could be slow).
      for (int c = 0; c < 8 && (all_neg || all_pos); ++c) {
        const Vec corner{{(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]}};
        const int side = format::filtered_orientation(f.planes[node.meta & kIndex], corner);
        all_neg &= side < 0;
        all_pos &= side > 0;
      }
    }
    if (!all_neg && !all_pos) break;
    n = all_pos ? node.right : n + 1;
  }
  return n;
}

/// About two grid cells per BSP node, cubes as near as the box allows, at most 2^21 in all. A
/// box whose extent or grid scale is not a finite, positive double on some axis (a span of
/// 1e-310, or of 2e308, which overflows) gets one grid cell: location then starts at the root,
/// which is right for any box, since the grid is only a shortcut.
void build_grid(vc_pvs& f) {
  double extent[3], volume = 1;
  bool usable = true;
  for (int k = 0; k < 3; ++k) {
    volume *= extent[k] = f.hi[k] - f.lo[k];
    usable &= std::isfinite(extent[k]) && extent[k] > 0 && std::isfinite(1.0 / extent[k]);
  }
  const double target = std::min<double>(2.0 * f.nodes.size(), 1 << 21);
  const double side = std::cbrt(volume / target);
  usable &= std::isfinite(volume) && side > 0 && std::isfinite(side);
  size_t total = 1;
  for (int k = 0; k < 3; ++k) {
    const double n = usable ? std::ceil(extent[k] / side) : 1.0;
    f.grid_n[k] = static_cast<int>(std::clamp(std::isfinite(n) ? n : 1.0, 1.0, 256.0));
    f.grid_scale[k] = usable ? f.grid_n[k] / extent[k] : 0.0;
    total *= static_cast<size_t>(f.grid_n[k]);
  }
  if (!usable) {
    f.grid_start.assign(1, 0);
    return;
  }
  f.grid_start.resize(total);
  // Each grid cell enlarged by far more than the rounding of a point's grid index, so that a
  // point given to a cell lies in its enlarged box.
  double margin[3];
  for (int k = 0; k < 3; ++k) margin[k] = 1e-9 * (std::fabs(f.lo[k]) + std::fabs(f.hi[k]) + extent[k]);
  size_t at = 0;
  for (int z = 0; z < f.grid_n[2]; ++z)
    for (int y = 0; y < f.grid_n[1]; ++y)
      for (int x = 0; x < f.grid_n[0]; ++x) {
        const int i[3] = {x, y, z};
        double lo[3], hi[3];
        // extent * (i / n), not extent * i / n: the product overflows for a span near 1e308
        // (a fuzzed file: its grid cells became [inf, inf] and sent location the wrong way).
        for (int k = 0; k < 3; ++k) {
          lo[k] = f.lo[k] + extent[k] * (static_cast<double>(i[k]) / f.grid_n[k]) - margin[k];
          hi[k] = f.lo[k] + extent[k] * (static_cast<double>(i[k] + 1) / f.grid_n[k]) + margin[k];
        }
        f.grid_start[at++] = deepest_node(f, lo, hi);
      }
}

}  // namespace

void read_file(const std::string& path, vc_pvs& f) {
  uint32_t version = 0;
  const std::string payload = read_container(path, version);  // sets version: before the call below
  read_payload(payload, version, f);
}

void read_bytes(const std::string& bytes, vc_pvs& f) {
  uint32_t version = 0;
  const std::string payload = decode_container(bytes, version);
  read_payload(payload, version, f);
}

void read_payload(const std::string& payload, uint32_t version, vc_pvs& f) {
  Reader r(payload);
  const uint64_t max_items = payload.size();
  f.fingerprint = r.get<uint64_t>();
  f.object_count = r.get<uint32_t>();
  const uint64_t names = r.get<uint64_t>();
  if (names != 0 && names != f.object_count) throw FileError("corrupt file: object names do not match the object count");
  for (uint64_t i = 0; i < names; ++i) f.names.push_back(r.get_string());
  f.rule = r.get_string();
  for (double& x : f.lo) x = r.get<double>();
  for (double& x : f.hi) x = r.get<double>();
  // As the toolkit checks it (Box3::volume): finite corners and a positive volume in double.
  bool box_ok = true;
  double volume = 1;
  for (int k = 0; k < 3; ++k) {
    box_ok &= std::isfinite(f.lo[k]) && std::isfinite(f.hi[k]) && f.lo[k] <= f.hi[k];
    volume *= f.hi[k] - f.lo[k];
  }
  if (!box_ok || !(volume > 0)) throw FileError("corrupt file: invalid view box");
  read_bsp(r, f, max_items);
  read_lists(r, f, max_items, version);
  for (Node& n : f.nodes) {
    if (n.right != 0) continue;
    if (n.meta >= f.cell_count) throw FileError("corrupt file: a BSP leaf has no view cell");
    if (f.compact) continue;  // no expanded lists to point at
    n.list[0] = static_cast<uint32_t>(f.offsets[n.meta]);
    n.list[1] = static_cast<uint32_t>(f.offsets[n.meta + 1] - f.offsets[n.meta]);
  }
  build_grid(f);
}

}  // namespace viewcells::runtime_detail
