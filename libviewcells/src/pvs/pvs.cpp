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
#include "viewcells/format/pvs_payload.h"

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

constexpr char kMagic[5] = "VPVS";
constexpr uint32_t kVersion = format::kPvsVersion;  // 2: lists by binary interpolative coding (id_lists.h)
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

format::PvsPayload payload_of(const PvsFile& f) {
  format::PvsPayload p;
  p.fingerprint = f.scene_fingerprint;
  p.object_count = f.object_count;
  p.names = f.object_names;
  p.rule = f.rule;
  const Subdivision& s = f.bsp;
  for (int k = 0; k < 3; ++k) {
    p.lo[k] = s.view_box.lo[k];
    p.hi[k] = s.view_box.hi[k];
  }
  for (const Plane& q : s.planes) {
    format::PvsPlane& out = p.planes.emplace_back();
    out.axis = q.axis;
    out.offset = q.offset;
    for (int k = 0; k < 3; ++k) {
      out.normal[k] = q.normal[k];
      for (int i = 0; i < 3; ++i) out.points[i][k] = q.points[i][k];
    }
  }
  for (size_t n = 0; n < s.nodes.size(); ++n)
    p.nodes.push_back({s.nodes[n].plane, {s.nodes[n].child[0], s.nodes[n].child[1]}, f.leaf_cell[n]});
  p.cell_count = f.pvs.cell_count;
  p.parent = f.pvs.parent;
  p.mht = f.cell_mht_node;
  p.stored = f.pvs.stored;
  return p;
}

std::string pvs_payload(const PvsFile& f, uint32_t version) {
  try {
    return format::encode_pvs_payload(payload_of(f), version);
  } catch (const format::FormatError& e) {
    throw Error(e.what());
  }
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
  format::PvsPayload p;
  try {
    p = format::decode_pvs_payload(payload, version);
  } catch (const format::FormatError& e) {
    throw Error(path, 0, e.what());
  }
  PvsFile f;
  f.scene_fingerprint = p.fingerprint;
  f.object_count = p.object_count;
  f.object_names = std::move(p.names);
  f.rule = std::move(p.rule);
  Subdivision& s = f.bsp;
  s.view_box.lo = {p.lo[0], p.lo[1], p.lo[2]};
  s.view_box.hi = {p.hi[0], p.hi[1], p.hi[2]};
  for (const format::PvsPlane& q : p.planes) {
    Plane& out = s.planes.emplace_back();
    out.axis = q.axis;
    out.normal = {q.normal[0], q.normal[1], q.normal[2]};
    out.offset = q.offset;
    for (int i = 0; i < 3; ++i) out.points[i] = {q.points[i][0], q.points[i][1], q.points[i][2]};
  }
  s.nodes.resize(p.nodes.size());
  f.leaf_cell.reserve(p.nodes.size());
  for (size_t n = 0; n < p.nodes.size(); ++n) {
    s.nodes[n].plane = p.nodes[n].plane;
    s.nodes[n].child[0] = p.nodes[n].child[0];
    s.nodes[n].child[1] = p.nodes[n].child[1];
    f.leaf_cell.push_back(p.nodes[n].cell);
  }
  f.pvs.cell_count = p.cell_count;
  f.pvs.parent = std::move(p.parent);
  f.cell_mht_node = std::move(p.mht);
  f.pvs.stored = std::move(p.stored);
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
