#pragma once
// The payload of a .pvs file (inside the container, container.h): the one codec that the
// toolkit's writer and reader (pvs/pvs.cpp) and the engines' reader (runtime/) all call, so that
// what one writes the others read alike, and a file either passes every check here or none of
// them reads it. Version 2 (version 1's lists are LEB128 varints: read, and written on request).
//   u64 scene fingerprint, u32 objects, u64 names (0 or the objects) and each name (u64 size,
//   bytes), the rule (string), the view box (lo, hi: 3 doubles each), u64 planes and each plane
//   (i32 axis: 0-2 or -1 for a general plane; normal, 3 doubles; offset, double; three points,
//   9 doubles), u64 BSP nodes and each (i32 plane or -1 for a leaf, i32 children, i32 view cell of
//   a leaf or -1), u32 view cells, the hierarchy's parents (u64 count, i32 each: cells first,
//   a parent after its children), each cell's merge-history node (u64 count, u32 each), and the
//   kept lists (string: each hierarchy node's list coded by id_lists.h in version 2).
// Little-endian throughout. Dependencies: none.
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/format/container.h"

namespace viewcells::format {

constexpr uint32_t kPvsVersion = 2;

struct PvsPlane {
  int32_t axis = 0;  ///< 0-2: axis-aligned; -1: general, sided exactly by its three points
  double normal[3] = {0, 0, 0};
  double offset = 0;
  double points[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
};

struct PvsNode {
  int32_t plane = -1;  ///< -1: a leaf
  int32_t child[2] = {-1, -1};
  int32_t cell = -1;   ///< a leaf's view cell; -1 for inner nodes
};

/// The payload, decoded. What decode_pvs_payload returns has passed every check: a box of
/// positive volume, finite planes, a BSP that is a tree (each inner node's children later and
/// each node but the root in it once), every leaf in a view cell, the hierarchy's parents
/// later than their children, every list sorted ids below the object count, and no cell whose
/// path through the hierarchy repeats an object.
struct PvsPayload {
  uint64_t fingerprint = 0;
  uint32_t object_count = 0;
  std::vector<std::string> names;  ///< empty, or one per object
  std::string rule;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  std::vector<PvsPlane> planes;
  std::vector<PvsNode> nodes;
  uint32_t cell_count = 0;
  std::vector<int32_t> parent;  ///< per hierarchy node (cells first)
  std::vector<uint32_t> mht;    ///< per cell, its merge-history node
  std::vector<std::vector<uint32_t>> stored;  ///< per hierarchy node, the ids it keeps
};

/// The payload's bytes in `version` (1 or kPvsVersion). FormatError when a list is not sorted
/// ids below the object count (the coding holds nothing else) or the version is unknown.
std::string encode_pvs_payload(const PvsPayload& p, uint32_t version);

/// The payload of a .pvs file of `version`, checked (see PvsPayload). FormatError, its message
/// "corrupt file: ..." naming what is wrong, otherwise; nothing in a payload makes it read out
/// of bounds, loop or allocate beyond what the payload's own size implies. With `node_bits`
/// (version 2 only), where each hierarchy node's coded list starts in `coded` (bits), and
/// `coded` the coded lists as stored, for a reader that keeps them coded.
PvsPayload decode_pvs_payload(const std::string& payload, uint32_t version, std::vector<uint64_t>* node_bits = nullptr,
                              std::string* coded = nullptr);

}  // namespace viewcells::format
