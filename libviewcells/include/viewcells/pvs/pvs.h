#pragma once
/// PVS compression by propagation up the view cell hierarchy (view-cell-construction paper,
/// section 5.2): each node of the merge history keeps the intersection of its children's
/// PVSs and the children drop it, so a view cell's PVS is the union of what the nodes on its
/// path to the root keep. Lossless. The `.pvs` file holds the compressed sets together with
/// what point location needs (the BSP and the cell of each leaf) and the object names, so
/// a viewer can be placed and its PVS read back from the file alone.
///
/// Also a flat form as game engines store it: one bit row over the objects per cell, its
/// zero bytes run-length coded as in Quake's vis data (a zero byte, then how many).
#include <cstdint>
#include <string>
#include <vector>

#include "viewcells/bsp/subdivision.h"
#include "viewcells/merge/merge.h"

namespace viewcells {

struct PvsHierarchy {
  uint32_t cell_count = 0;                    ///< nodes 0 .. cell_count-1 are the view cells
  std::vector<int32_t> parent;                ///< per node; -1 for a root; parent > node
  std::vector<std::vector<uint32_t>> stored;  ///< per node: the object ids kept there, sorted

  size_t node_count() const { return parent.size(); }
  /// The PVS of view cell `cell`: the union along its path to the root, sorted.
  std::vector<uint32_t> cell_pvs(uint32_t cell) const;
  uint64_t stored_entries() const;
};

/// Compresses the PVSs of the view cells `cells` (MHT nodes of `h` forming a cut, with
/// `cell_pvs[i]` the sorted PVS of cells[i]) through the part of the merge history above them.
PvsHierarchy compress_pvs(const MergeHistory& h, const std::vector<int32_t>& cells,
                          const std::vector<std::vector<uint32_t>>& cell_pvs);

/// The hierarchy `shape` (its cells and merge nodes, each parent after its children) holding the
/// cells' PVSs `cell_pvs` instead (sorted ids, one list per cell): each merge node keeps the
/// intersection of its children's, as compress_pvs. Error when a list is not sorted or the
/// count differs.
PvsHierarchy recompress_pvs(const PvsHierarchy& shape, const std::vector<std::vector<uint32_t>>& cell_pvs);

/// Bytes of sorted id lists below `object_count` as the .pvs file codes them (binary
/// interpolative coding, format/include/viewcells/format/id_lists.h; before the container's zstd, which finds
/// little more in them). Linear in the entries. `format` 1 gives what format 1 took (LEB128
/// varints of the differences).
uint64_t list_bytes(const std::vector<std::vector<uint32_t>>& lists, uint32_t object_count, uint32_t format = 2);

/// The bytes of the visible sets in an engine's compact handle of this hierarchy (the runtime's
/// vc_pvs_open_compact): the coded lists (list_bytes) and 8 bytes a hierarchy node (where its
/// list starts, its parent). What stands against a map compiler's vis rows.
uint64_t compact_pvs_bytes(const PvsHierarchy& h, uint32_t object_count);

/// One Quake-style row: bit o set for every object o of `pvs`, then zero bytes coded as
/// (0, run length <= 255).
std::string rle_row(const std::vector<uint32_t>& pvs, uint32_t object_count);
/// The inverse of rle_row; throws Error on a malformed row.
std::vector<uint32_t> unrle_row(const std::string& row, uint32_t object_count);

struct PvsFile {
  PvsHierarchy pvs;
  /// Point location: the view box, the BSP's planes and nodes (plane, children), and the
  /// view cell of each BSP leaf (-1 for inner nodes).
  Subdivision bsp;
  std::vector<int32_t> leaf_cell;
  std::vector<uint32_t> cell_mht_node;  ///< per view cell: its node in the merge history
  uint32_t object_count = 0;
  std::vector<std::string> object_names;  ///< empty, or one per object
  uint64_t scene_fingerprint = 0;
  std::string rule;  ///< how the view cells were chosen

  /// The view cell containing p, or -1 outside the view space.
  int32_t locate(const Vec3& p) const;
};

/// The .pvs file for the view cells `cells` of merge history `h` over the leaves of `s`;
/// `leaf_pvs` per BSP node as in SubdivisionFile. The BSP is copied without cells/segments.
PvsFile make_pvs_file(const Subdivision& s, const std::vector<std::vector<uint32_t>>& leaf_pvs,
                      const MergeHistory& h, const std::vector<int32_t>& cells);

/// Writes a versioned, checksummed `.pvs` file (atomically), in format 2 or, for engines whose
/// runtime reader predates it, format 1. Error when a kept list is not sorted ids below
/// f.object_count.
void write_pvs(const std::string& path, const PvsFile& f, uint32_t format = 2);
/// The bytes write_pvs writes for `f` (format 2), in memory.
std::string pvs_file_image(const PvsFile& f);
/// The size in bytes of the file write_pvs writes for `f`, measured without writing it.
uint64_t pvs_file_bytes(const PvsFile& f);
/// Reads and validates a `.pvs` file of any format this build reads (1 and 2; `format`, when
/// given, receives the file's); any inconsistency is an Error naming the file.
PvsFile read_pvs(const std::string& path, uint32_t* format = nullptr);

/// Writes the flat rows of every view cell (Quake-style run-length coding) as a checksummed
/// container; returns the bytes of the rows (without the container's own compression).
uint64_t write_flat_rows(const std::string& path, const PvsFile& f);

}  // namespace viewcells
