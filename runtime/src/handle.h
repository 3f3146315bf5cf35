#pragma once
// The runtime's handle (runtime.h's opaque vc_pvs): the BSP as location walks it, the general
// planes, the visible sets (expanded, or coded for a compact handle) and the grid where
// location starts. Internal to the runtime's files:
//   container.cpp    the .pvs container read (the format: format/, shared with the toolkit)
//   load.cpp         the payload read into a handle, every count and index checked
//   c_api.cpp        the C API (runtime.h)
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <string>
#include <sys/mman.h>
#include <vector>

#include "viewcells/format/orientation.h"
#include "viewcells/runtime.h"

namespace viewcells::runtime_detail {

using format::Vec;

/// A BSP node as location walks it: 16 bytes, laid out in preorder so that the negative
/// child follows its parent. `right` is the positive child, or 0 for a leaf (the root is
/// never a child). An inner node compares coordinate `meta >> 30` (0-2) with `offset`, or
/// when that is 3 asks the exact predicate of general plane `meta & kIndex`. A leaf's `meta`
/// is its view cell, and `list` locates the cell's visible objects in the ids array.
struct Node {
  union {
    double offset;
    uint32_t list[2];  // first, count
  };
  uint32_t meta;
  uint32_t right;
};
constexpr uint32_t kIndex = (1u << 30) - 1;

using format::GeneralPlane;

/// Memory for the large arrays that every query touches at random (the visible sets, the
/// BSP): 2 MB aligned and, on Linux, marked for transparent huge pages, so that a lookup does
/// not also pay a page-table walk for each 4 KB page it lands on.
template <class T>
struct LargePages {
  using value_type = T;
  LargePages() = default;
  template <class U>
  LargePages(const LargePages<U>&) {}
  static constexpr size_t kAlign = size_t{2} << 20;
  T* allocate(size_t n) {
    if (n > std::numeric_limits<size_t>::max() / sizeof(T) - kAlign) throw std::bad_alloc();
    const size_t bytes = n * sizeof(T);
    if (bytes < kAlign) {
      void* p = std::malloc(bytes ? bytes : 1);
      if (!p) throw std::bad_alloc();
      return static_cast<T*>(p);
    }
    const size_t rounded = (bytes + kAlign - 1) / kAlign * kAlign;
    void* p = std::aligned_alloc(kAlign, rounded);
    if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(p, rounded, MADV_HUGEPAGE);  // advice only: without huge pages it still works
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t) { std::free(p); }
  template <class U>
  bool operator==(const LargePages<U>&) const { return true; }
  template <class U>
  bool operator!=(const LargePages<U>&) const { return false; }
};

/// Reads and checks the .pvs file `path` into `f` (FileError on any inconsistency).
void read_file(const std::string& path, vc_pvs& f);
/// The same from the file's bytes in memory.
void read_bytes(const std::string& bytes, vc_pvs& f);
/// The same from the payload of a container of format `version`.
void read_payload(const std::string& payload, uint32_t version, vc_pvs& f);

}  // namespace viewcells::runtime_detail

struct vc_pvs {
  uint64_t fingerprint = 0;
  uint32_t object_count = 0;
  uint32_t cell_count = 0;
  std::vector<std::string> names;
  std::string rule;
  double lo[3], hi[3];
  std::vector<viewcells::runtime_detail::Node, viewcells::runtime_detail::LargePages<viewcells::runtime_detail::Node>> nodes;
  std::vector<viewcells::runtime_detail::GeneralPlane> planes;
  std::vector<uint64_t> offsets;               // per cell + 1, into ids
  std::vector<uint32_t, viewcells::runtime_detail::LargePages<uint32_t>> ids;  // every cell's visible objects, sorted per cell
  // A compact handle (vc_pvs_open_compact) keeps the hierarchy's lists coded instead of ids and
  // offsets: the format 2 coding of every node's list, where each starts (in bits), and each
  // node's parent. A cell's visible set is decoded along its path when asked for.
  bool compact = false;
  std::string coded;
  std::vector<uint32_t> node_bit;
  std::vector<int32_t> node_parent;
  // A uniform grid over the view box: per grid cell, the deepest BSP node whose subtree holds
  // the whole grid cell (slightly enlarged), where location starts instead of at the root.
  int grid_n[3] = {1, 1, 1};
  double grid_scale[3] = {0, 0, 0};
  std::vector<uint32_t> grid_start;
};
