/// PVS compression through the view cell hierarchy (view-cell-construction paper, section 5.2) and
/// the .pvs file.
#include "viewcells/pvs/pvs.h"

#include <algorithm>
#include <iterator>
#include <map>

#include "viewcells/cells/view_cells.h"
#include "viewcells/bsp/bsp_io.h"
#include "viewcells/core/error.h"
#include "viewcells/core/binary_file.h"
#include "viewcells/format/id_lists.h"

namespace viewcells {

std::vector<uint32_t> PvsHierarchy::cell_pvs(uint32_t cell) const {
  VC_CHECK(cell < cell_count);
  std::vector<uint32_t> out;
  // What the nodes of a path keep is disjoint, so the union is a concatenation.
  for (int32_t n = static_cast<int32_t>(cell); n >= 0; n = parent[n]) out.insert(out.end(), stored[n].begin(), stored[n].end());
  std::sort(out.begin(), out.end());
  return out;
}

uint64_t PvsHierarchy::stored_entries() const {
  uint64_t n = 0;
  for (const auto& s : stored) n += s.size();
  return n;
}

namespace {

/// What each node of `out` keeps, given every node's whole PVS `full`: a root all of it, any
/// other node what its parent's lacks (so a cell's PVS is the union along its path).
void keep_differences(const std::vector<std::vector<uint32_t>>& full, PvsHierarchy& out) {
  out.stored.assign(full.size(), {});
  for (size_t n = 0; n < full.size(); ++n) {
    if (out.parent[n] < 0) {
      out.stored[n] = full[n];
      continue;
    }
    const auto& up = full[out.parent[n]];
    std::set_difference(full[n].begin(), full[n].end(), up.begin(), up.end(), std::back_inserter(out.stored[n]));
  }
}

}  // namespace

PvsHierarchy compress_pvs(const MergeHistory& h, const std::vector<int32_t>& cells,
                          const std::vector<std::vector<uint32_t>>& cell_pvs) {
  if (cells.size() != cell_pvs.size()) throw Error("compress_pvs: one PVS per cell is needed");
  // Nodes: the cells first, then every merge node above them, children before parents.
  std::map<int32_t, int32_t> index;  // MHT node -> hierarchy node
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] < 0 || cells[i] >= static_cast<int32_t>(h.nodes.size())) throw Error("compress_pvs: no such cell");
    if (!index.emplace(cells[i], static_cast<int32_t>(i)).second) throw Error("compress_pvs: a cell is listed twice");
  }
  std::vector<int32_t> above;
  for (int32_t c : cells)
    for (int32_t n = h.nodes[c].parent; n >= 0; n = h.nodes[n].parent) {
      if (index.count(n) && index[n] < static_cast<int32_t>(cells.size()))
        throw Error("compress_pvs: the cells overlap (one lies inside another)");
      above.push_back(n);
    }
  std::sort(above.begin(), above.end());
  above.erase(std::unique(above.begin(), above.end()), above.end());
  for (int32_t n : above) index.emplace(n, static_cast<int32_t>(index.size()));

  PvsHierarchy out;
  out.cell_count = static_cast<uint32_t>(cells.size());
  const size_t total = cells.size() + above.size();
  out.parent.assign(total, -1);
  std::vector<std::vector<uint32_t>> full(total);
  for (size_t i = 0; i < cells.size(); ++i) {
    full[i] = cell_pvs[i];
    if (!std::is_sorted(full[i].begin(), full[i].end())) throw Error("compress_pvs: PVSs must be sorted");
  }
  for (int32_t n : above) {  // increasing MHT ids: children are done before their parent
    const int32_t me = index[n];
    const auto c0 = index.find(h.nodes[n].child[0]), c1 = index.find(h.nodes[n].child[1]);
    if (c0 == index.end() || c1 == index.end())
      throw Error("compress_pvs: the cells do not cover the merge node " + std::to_string(n) + " (not a cut)");
    std::set_intersection(full[c0->second].begin(), full[c0->second].end(), full[c1->second].begin(),
                          full[c1->second].end(), std::back_inserter(full[me]));
    out.parent[c0->second] = me;
    out.parent[c1->second] = me;
  }
  keep_differences(full, out);
  return out;
}

namespace {

/// Version 1's lists: each a LEB128 varint count, then the differences between successive ids
/// (minus one) as varints. Read for files written before version 2, written on request for
/// engines whose reader predates it.
void put_varint(std::string& out, uint32_t v) {
  for (; v >= 0x80; v >>= 7) out.push_back(static_cast<char>((v & 0x7f) | 0x80));
  out.push_back(static_cast<char>(v));
}

std::string varint_lists(const std::vector<std::vector<uint32_t>>& lists) {
  std::string out;
  for (const auto& l : lists) {
    put_varint(out, static_cast<uint32_t>(l.size()));
    for (size_t i = 0; i < l.size(); ++i) put_varint(out, i ? l[i] - l[i - 1] - 1 : l[i]);
  }
  return out;
}

uint32_t get_varint(ByteReader& r) {
  uint32_t v = 0;
  for (int shift = 0; shift < 35; shift += 7) {
    const uint8_t b = r.get<uint8_t>();
    v |= static_cast<uint32_t>(b & 0x7f) << shift;
    if (!(b & 0x80)) return v;
  }
  r.fail("malformed varint");
}

std::vector<uint32_t> decode_varint_list(ByteReader& r, uint32_t object_count) {
  const uint32_t n = get_varint(r);
  if (n > object_count) r.fail("a list holds more entries than there are objects");
  std::vector<uint32_t> ids(n);
  uint64_t previous = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t id = (i ? previous + 1 : 0) + get_varint(r);
    if (id >= object_count) r.fail("object id " + std::to_string(id) + " out of range");
    ids[i] = static_cast<uint32_t>(id);
    previous = id;
  }
  return ids;
}

constexpr char kMagic[5] = "VPVS";
constexpr uint32_t kVersion = 2;  // 2: lists by binary interpolative coding (id_lists.h)
constexpr char kFlatMagic[5] = "VFLT";

}  // namespace

PvsHierarchy recompress_pvs(const PvsHierarchy& shape, const std::vector<std::vector<uint32_t>>& cell_pvs) {
  if (cell_pvs.size() != shape.cell_count) throw Error("recompress_pvs: one PVS per view cell is needed");
  const size_t total = shape.node_count();
  std::vector<std::vector<uint32_t>> full(total);
  std::vector<bool> filled(total, false);
  for (size_t c = 0; c < cell_pvs.size(); ++c) {
    if (!std::is_sorted(cell_pvs[c].begin(), cell_pvs[c].end()) ||
        std::adjacent_find(cell_pvs[c].begin(), cell_pvs[c].end()) != cell_pvs[c].end())
      throw Error("recompress_pvs: the PVS of cell " + std::to_string(c) + " is not sorted distinct ids");
    full[c] = cell_pvs[c];
    filled[c] = true;
  }
  for (size_t n = 0; n < total; ++n) {  // children come before their parent
    const int32_t p = shape.parent[n];
    if (p < 0) continue;
    if (!filled[p]) {
      full[p] = full[n];
      filled[p] = true;
    } else {
      std::vector<uint32_t> both;
      std::set_intersection(full[p].begin(), full[p].end(), full[n].begin(), full[n].end(), std::back_inserter(both));
      full[p].swap(both);
    }
  }
  PvsHierarchy out;
  out.cell_count = shape.cell_count;
  out.parent = shape.parent;
  keep_differences(full, out);
  return out;
}

uint64_t list_bytes(const std::vector<std::vector<uint32_t>>& lists, uint32_t object_count, uint32_t format) {
  VC_CHECK(format == 1 || format == kVersion);
  for (const auto& l : lists)
    for (size_t i = 0; i < l.size(); ++i) VC_CHECK(l[i] < object_count && (i == 0 || l[i - 1] < l[i]));
  if (format == 1) return varint_lists(lists).size();
  return id_lists::encoded_bytes(lists, object_count);
}

uint64_t compact_pvs_bytes(const PvsHierarchy& h, uint32_t object_count) {
  return list_bytes(h.stored, object_count) + 8 * static_cast<uint64_t>(h.node_count());
}

std::string rle_row(const std::vector<uint32_t>& pvs, uint32_t object_count) {
  std::string bits((object_count + 7) / 8, '\0');
  for (uint32_t o : pvs) {
    VC_CHECK(o < object_count);
    bits[o >> 3] = static_cast<char>(bits[o >> 3] | (1 << (o & 7)));
  }
  std::string out;
  for (size_t i = 0; i < bits.size();) {
    if (bits[i]) {
      out.push_back(bits[i++]);
      continue;
    }
    size_t run = 0;
    while (i < bits.size() && !bits[i] && run < 255) ++i, ++run;
    out.push_back('\0');
    out.push_back(static_cast<char>(run));
  }
  return out;
}

std::vector<uint32_t> unrle_row(const std::string& row, uint32_t object_count) {
  const size_t bytes = (object_count + 7) / 8;
  std::vector<uint32_t> out;
  size_t at = 0;
  for (size_t i = 0; i < row.size(); ++i) {
    const uint8_t b = static_cast<uint8_t>(row[i]);
    if (b == 0) {
      if (i + 1 >= row.size() || row[i + 1] == 0) throw Error("malformed run-length row");
      at += static_cast<uint8_t>(row[++i]);
      continue;
    }
    if (at >= bytes) throw Error("run-length row longer than its objects");
    for (int k = 0; k < 8; ++k)
      if (b & (1 << k)) out.push_back(static_cast<uint32_t>(8 * at + k));
    ++at;
  }
  if (at != bytes) throw Error("run-length row of the wrong length");
  if (!out.empty() && out.back() >= object_count) throw Error("run-length row names objects that do not exist");
  return out;
}

int32_t PvsFile::locate(const Vec3& p) const { return locate_cell(bsp, leaf_cell, p); }

PvsFile make_pvs_file(const Subdivision& s, const std::vector<std::vector<uint32_t>>& leaf_pvs,
                      const MergeHistory& h, const std::vector<int32_t>& cells) {
  const std::vector<int32_t> leaves = s.leaves();
  if (leaves.size() != h.leaf_count) throw Error("the merge history does not match the subdivision");
  PvsFile f;
  std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
  std::vector<std::vector<uint32_t>> cell_pvs(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    auto& pvs = cell_pvs[i];
    for (uint32_t leaf : h.leaves_under(cells[i])) {
      if (leaf_cell[leaves[leaf]] != -1) throw Error("the view cells overlap");
      leaf_cell[leaves[leaf]] = static_cast<int32_t>(i);
      pvs.insert(pvs.end(), leaf_pvs[leaves[leaf]].begin(), leaf_pvs[leaves[leaf]].end());
    }
    std::sort(pvs.begin(), pvs.end());
    pvs.erase(std::unique(pvs.begin(), pvs.end()), pvs.end());
    f.cell_mht_node.push_back(static_cast<uint32_t>(cells[i]));
  }
  for (int32_t leaf : leaves)
    if (leaf_cell[leaf] < 0) throw Error("the view cells do not cover the view space");
  f.pvs = compress_pvs(h, cells, cell_pvs);

  // Point location needs only the BSP's subtrees that straddle view cells: a subtree whose
  // leaves all lie in one cell becomes one leaf. Children have larger ids than their parent,
  // so a backward pass sees children first.
  std::vector<int32_t> uniform(s.nodes.size(), -1);  // the subtree's single cell, or -1
  for (size_t n = s.nodes.size(); n-- > 0;) {
    const BspNode& b = s.nodes[n];
    if (b.plane < 0) {
      uniform[n] = leaf_cell[n];
    } else if (uniform[b.child[0]] >= 0 && uniform[b.child[0]] == uniform[b.child[1]]) {
      uniform[n] = uniform[b.child[0]];
    }
  }
  f.bsp.view_box = s.view_box;
  f.bsp.planes.assign(s.planes.begin(), s.planes.begin() + 6);  // the box faces stay
  std::vector<int32_t> plane_id(s.planes.size(), -1);
  // Preorder copy: a parent gets its index before its children, as in the original.
  std::vector<std::pair<int32_t, int32_t>> stack = {{0, -1}};  // (old node, new parent's slot)
  while (!stack.empty()) {
    const auto [old, slot] = stack.back();
    stack.pop_back();
    const int32_t me = static_cast<int32_t>(f.bsp.nodes.size());
    if (slot >= 0) f.bsp.nodes[slot / 2].child[slot % 2] = me;
    BspNode node;
    node.parent = slot >= 0 ? slot / 2 : -1;
    if (uniform[old] >= 0) {
      f.bsp.nodes.push_back(node);
      f.leaf_cell.push_back(uniform[old]);
      continue;
    }
    const int32_t p = s.nodes[old].plane;
    if (plane_id[p] < 0) {
      plane_id[p] = static_cast<int32_t>(f.bsp.planes.size());
      f.bsp.planes.push_back(s.planes[p]);
    }
    node.plane = plane_id[p];
    f.bsp.nodes.push_back(node);
    f.leaf_cell.push_back(-1);
    stack.push_back({s.nodes[old].child[1], 2 * me + 1});
    stack.push_back({s.nodes[old].child[0], 2 * me});
  }
  return f;
}

namespace {

std::string pvs_payload(const PvsFile& f, uint32_t format) {
  ByteWriter w;
  w.put<uint64_t>(f.scene_fingerprint);
  w.put<uint32_t>(f.object_count);
  w.put<uint64_t>(f.object_names.size());
  for (const std::string& n : f.object_names) w.put_string(n);
  w.put_string(f.rule);
  // Point location.
  const Subdivision& s = f.bsp;
  w.put(s.view_box.lo);
  w.put(s.view_box.hi);
  put_planes(w, s.planes);
  w.put<uint64_t>(s.nodes.size());
  for (size_t n = 0; n < s.nodes.size(); ++n) {
    w.put<int32_t>(s.nodes[n].plane);
    w.put<int32_t>(s.nodes[n].child[0]);
    w.put<int32_t>(s.nodes[n].child[1]);
    w.put<int32_t>(f.leaf_cell[n]);
  }
  // The hierarchy: cells first, parents, then the kept lists.
  w.put<uint32_t>(f.pvs.cell_count);
  w.put_array(f.pvs.parent);
  w.put_array(f.cell_mht_node);
  // The coding holds only sorted ids below the object count: refuse to write anything else.
  for (size_t n = 0; n < f.pvs.stored.size(); ++n) {
    const std::vector<uint32_t>& l = f.pvs.stored[n];
    for (size_t i = 0; i < l.size(); ++i)
      if (l[i] >= f.object_count || (i && l[i - 1] >= l[i]))
        throw Error("the PVS list of hierarchy node " + std::to_string(n) + " is not sorted ids below the " +
                    std::to_string(f.object_count) + " objects");
  }
  w.put_string(format == 1 ? varint_lists(f.pvs.stored) : id_lists::encode(f.pvs.stored, f.object_count));
  return w.data();
}

}  // namespace

void write_pvs(const std::string& path, const PvsFile& f, uint32_t format) {
  if (format != 1 && format != kVersion)
    throw Error(path, 0, "cannot write .pvs format " + std::to_string(format) + " (1 or " + std::to_string(kVersion) + ")");
  write_container(path, kMagic, format, pvs_payload(f, format));
}

std::string pvs_file_image(const PvsFile& f) { return container_image(kMagic, kVersion, pvs_payload(f, kVersion)); }

uint64_t pvs_file_bytes(const PvsFile& f) { return pvs_file_image(f).size(); }

PvsFile read_pvs(const std::string& path, uint32_t* format) {
  uint32_t version = 0;
  const std::string payload = read_container(path, kMagic, kVersion, version);
  if (format) *format = version;
  ByteReader r(payload, path);
  PvsFile f;
  const uint64_t max_items = payload.size();
  f.scene_fingerprint = r.get<uint64_t>();
  f.object_count = r.get<uint32_t>();
  const uint64_t names = r.get<uint64_t>();
  if (names != 0 && names != f.object_count) r.fail("object names do not match the object count");
  for (uint64_t i = 0; i < names; ++i) f.object_names.push_back(r.get_string());
  f.rule = r.get_string();
  Subdivision& s = f.bsp;
  s.view_box = get_view_box(r);
  s.planes = get_planes(r, max_items);
  const uint64_t planes = s.planes.size();
  const uint64_t nodes = r.get<uint64_t>();
  if (nodes == 0 || nodes > max_items || nodes % 2 == 0) r.fail("invalid node count");
  s.nodes.resize(nodes);
  f.leaf_cell.resize(nodes);
  for (size_t n = 0; n < nodes; ++n) {
    BspNode& b = s.nodes[n];
    b.plane = r.get<int32_t>();
    b.child[0] = r.get<int32_t>();
    b.child[1] = r.get<int32_t>();
    f.leaf_cell[n] = r.get<int32_t>();
  }
  f.pvs.cell_count = r.get<uint32_t>();
  r.get_array(f.pvs.parent, max_items);
  r.get_array(f.cell_mht_node, max_items);
  const std::string lists = r.get_string();
  if (!r.at_end()) r.fail("trailing bytes");
  // The BSP: every inner node has a plane and two later children, each child one parent.
  const size_t total = f.pvs.parent.size();
  if (f.pvs.cell_count == 0 || f.pvs.cell_count > total || f.cell_mht_node.size() != f.pvs.cell_count)
    r.fail("invalid view cell count");
  std::vector<int> parents(nodes, 0);
  for (size_t n = 0; n < nodes; ++n) {
    const BspNode& b = s.nodes[n];
    if (b.plane < 0) {
      if (b.child[0] != -1 || b.child[1] != -1) r.fail("BSP leaf " + std::to_string(n) + " has children");
      if (f.leaf_cell[n] < 0 || f.leaf_cell[n] >= static_cast<int32_t>(f.pvs.cell_count))
        r.fail("BSP leaf " + std::to_string(n) + " has no view cell");
      continue;
    }
    if (b.plane >= static_cast<int32_t>(planes) || f.leaf_cell[n] != -1) r.fail("BSP node " + std::to_string(n) + " is invalid");
    for (int32_t c : b.child) {
      if (c <= static_cast<int32_t>(n) || c >= static_cast<int32_t>(nodes)) r.fail("BSP node " + std::to_string(n) + " has a bad child");
      ++parents[c];
    }
  }
  for (size_t n = 1; n < nodes; ++n)
    if (parents[n] != 1) r.fail("BSP node " + std::to_string(n) + " is not in the tree once");
  // The hierarchy: parents come later; lists decode to sorted ids within the object count.
  for (size_t n = 0; n < total; ++n) {
    const int32_t p = f.pvs.parent[n];
    if (p != -1 && (p <= static_cast<int32_t>(n) || p >= static_cast<int32_t>(total)))
      r.fail("hierarchy node " + std::to_string(n) + " has a bad parent");
  }
  f.pvs.stored.resize(total);
  if (version == 1) {
    ByteReader lr(lists, path);
    for (auto& l : f.pvs.stored) l = decode_varint_list(lr, f.object_count);
    if (!lr.at_end()) r.fail("trailing bytes after the PVS lists");
  } else {
    id_lists::BitReader lr(lists.data(), lists.size());
    for (size_t n = 0; n < total; ++n)
      if (!id_lists::get_list(lr, f.object_count, f.pvs.stored[n]))
        r.fail("malformed PVS list of hierarchy node " + std::to_string(n));
    if (!lr.at_end()) r.fail("trailing bytes after the PVS lists");
  }
  for (uint32_t c = 0; c < f.pvs.cell_count; ++c) {
    // Kept lists along a path are disjoint by construction; a repeat means corruption.
    const std::vector<uint32_t> pvs = f.pvs.cell_pvs(c);
    if (std::adjacent_find(pvs.begin(), pvs.end()) != pvs.end()) r.fail("cell " + std::to_string(c) + " repeats an object");
  }
  return f;
}

uint64_t write_flat_rows(const std::string& path, const PvsFile& f) {
  ByteWriter w;
  w.put<uint32_t>(f.pvs.cell_count);
  w.put<uint32_t>(f.object_count);
  std::string rows;
  std::vector<uint64_t> offsets;
  for (uint32_t c = 0; c < f.pvs.cell_count; ++c) {
    offsets.push_back(rows.size());
    rows += rle_row(f.pvs.cell_pvs(c), f.object_count);
  }
  offsets.push_back(rows.size());
  w.put_array(offsets);
  w.put_string(rows);
  write_container(path, kFlatMagic, 1, w.data());
  return rows.size();
}

}  // namespace viewcells
