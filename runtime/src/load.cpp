// The payload of a .pvs file read into a handle (handle.h): decoded and checked by the format's
// codec (format/pvs_payload.h, the toolkit's reader too), then laid out for location: the BSP in
// preorder, the general planes, the visible sets (expanded, or kept coded for a compact handle),
// names, and the grid where location starts.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "container.h"
#include "handle.h"
#include "viewcells/format/id_lists.h"
#include "viewcells/format/orientation.h"
#include "viewcells/format/pvs_payload.h"

namespace viewcells::runtime_detail {

namespace {

/// The BSP in preorder (the codec checked that it is a tree whose leaves are view cells), and
/// the general planes, within what a handle indexes.
void read_bsp(const format::PvsPayload& p, vc_pvs& f) {
  std::vector<int32_t> general(p.planes.size(), -1);
  for (size_t i = 0; i < p.planes.size(); ++i) {
    const format::PvsPlane& q = p.planes[i];
    if (q.axis >= 0) continue;
    general[i] = static_cast<int32_t>(f.planes.size());
    f.planes.push_back(GeneralPlane{{{q.points[0][0], q.points[0][1], q.points[0][2]}},
                                    {{q.points[1][0], q.points[1][1], q.points[1][2]}},
                                    {{q.points[2][0], q.points[2][1], q.points[2][2]}}});
  }
  if (p.nodes.size() >= kIndex) throw FileError("corrupt file: invalid node count");
  if (f.planes.size() > kIndex) throw FileError("corrupt file: invalid plane count");
  // Preorder layout (a tree): the negative child right after its parent.
  f.nodes.reserve(p.nodes.size());
  std::vector<std::pair<int32_t, int64_t>> stack = {{0, -1}};  // (file node, parent's slot for `right`)
  while (!stack.empty()) {
    const auto [old, slot] = stack.back();
    stack.pop_back();
    const uint32_t me = static_cast<uint32_t>(f.nodes.size());
    if (slot >= 0) f.nodes[slot].right = me;
    Node node{};
    node.right = 0;
    const format::PvsNode& b = p.nodes[old];
    if (b.plane < 0) {
      node.meta = static_cast<uint32_t>(b.cell);
      node.list[0] = node.list[1] = 0;
      f.nodes.push_back(node);
      continue;
    }
    const format::PvsPlane& q = p.planes[b.plane];
    node.offset = q.offset;
    node.meta = q.axis >= 0 ? static_cast<uint32_t>(q.axis) << 30 : (3u << 30) | static_cast<uint32_t>(general[b.plane]);
    f.nodes.push_back(node);
    stack.push_back({b.child[1], me});
    stack.push_back({b.child[0], -1});  // popped next: lands at me + 1
  }
}

/// Every cell's visible set expanded, or for a compact handle the lists kept coded (format 2:
/// version 1's lists coded again) with where each node's starts.
void read_lists(format::PvsPayload& p, vc_pvs& f, std::vector<uint64_t>& node_bits, std::string& coded) {
  f.cell_count = p.cell_count;
  if (f.compact) {
    if (coded.empty() && node_bits.empty()) {  // version 1: code the lists as format 2's
      viewcells::id_lists::BitWriter w;
      for (const auto& ids : p.stored) {
        node_bits.push_back(w.bits());
        viewcells::id_lists::put_list(w, ids.data(), ids.size(), f.object_count);
      }
      coded = w.finish();
    }
    if (8 * static_cast<uint64_t>(coded.size()) > std::numeric_limits<uint32_t>::max())
      throw FileError("the coded lists exceed 2^32 bits, more than a compact handle indexes");
    f.node_bit.assign(node_bits.begin(), node_bits.end());
    f.coded = std::move(coded);
    f.node_parent = std::move(p.parent);
    return;
  }
  uint64_t expanded = 0;
  for (uint32_t c = 0; c < f.cell_count; ++c)
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = p.parent[n]) expanded += p.stored[n].size();
  if (expanded > (uint64_t{1} << 31))
    throw FileError("the expanded visible sets hold " + std::to_string(expanded) + " entries, more than 2^31");
  f.offsets.reserve(f.cell_count + 1);
  f.ids.reserve(expanded);
  f.offsets.push_back(0);
  for (uint32_t c = 0; c < f.cell_count; ++c) {
    const size_t first = f.ids.size();
    for (int32_t n = static_cast<int32_t>(c); n >= 0; n = p.parent[n])
      f.ids.insert(f.ids.end(), p.stored[n].begin(), p.stored[n].end());
    std::sort(f.ids.begin() + first, f.ids.end());
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
  std::vector<uint64_t> node_bits;
  std::string coded;
  format::PvsPayload p;
  try {
    p = format::decode_pvs_payload(payload, version, f.compact ? &node_bits : nullptr, f.compact ? &coded : nullptr);
  } catch (const format::FormatError& e) {
    throw FileError(e.what());
  }
  f.fingerprint = p.fingerprint;
  f.object_count = p.object_count;
  f.names = std::move(p.names);
  f.rule = std::move(p.rule);
  for (int k = 0; k < 3; ++k) {
    f.lo[k] = p.lo[k];
    f.hi[k] = p.hi[k];
  }
  read_bsp(p, f);
  read_lists(p, f, node_bits, coded);
  for (Node& n : f.nodes) {
    if (n.right != 0 || f.compact) continue;  // a compact handle has no expanded lists to point at
    n.list[0] = static_cast<uint32_t>(f.offsets[n.meta]);
    n.list[1] = static_cast<uint32_t>(f.offsets[n.meta + 1] - f.offsets[n.meta]);
  }
  build_grid(f);
}

}  // namespace viewcells::runtime_detail
