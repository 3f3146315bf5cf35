// The runtime's C API (viewcells/runtime.h): handles opened from .pvs files, point location,
// and a cell's visible objects as ids, copies or bit rows. Every function takes a NULL handle.
#include "viewcells/runtime.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "container.h"
#include "handle.h"
#include "viewcells/format/id_lists.h"
#include "viewcells/format/orientation.h"

using viewcells::runtime_detail::FileError;
using viewcells::runtime_detail::GeneralPlane;
using viewcells::runtime_detail::kIndex;
using viewcells::runtime_detail::Node;
using viewcells::format::orientation;
using viewcells::runtime_detail::read_bytes;
using viewcells::runtime_detail::read_file;
using viewcells::runtime_detail::Vec;

namespace {

void put_error(char* error, size_t size, const std::string& text) {
  if (!error || size == 0) return;
  std::snprintf(error, size, "%s", text.c_str());
}

}  // namespace

extern "C" {

namespace {

/// Opens a handle from the file `path`, or from `size` bytes at `bytes` when `path` is null
/// (named `name` in messages).
int open_handle(const char* path, const void* bytes, size_t size, vc_pvs** out, char* error, size_t error_size,
                bool compact) {
  const char* name = path ? path : "(memory)";
  if (out) *out = nullptr;
  if ((!path && !bytes) || !out) {
    put_error(error, error_size, path || bytes ? "vc_pvs_open: out must not be NULL"
                                               : "vc_pvs_open: the path (or the bytes) and out must not be NULL");
    return 1;
  }
  vc_pvs* f = nullptr;
  try {
    f = new vc_pvs;
    f->compact = compact;
    if (path)
      read_file(path, *f);
    else
      read_bytes(std::string(static_cast<const char*>(bytes), size), *f);
  } catch (const FileError& e) {
    delete f;
    put_error(error, error_size, std::string(name) + ": " + e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    delete f;
    put_error(error, error_size, std::string(name) + ": out of memory");
    return 3;
  } catch (const std::exception& e) {
    delete f;
    put_error(error, error_size, std::string(name) + ": " + e.what());
    return 4;
  }
  *out = f;
  return 0;
}

/// A compact handle's cell: the lists along its path decoded into `out`, sorted. The lists of a
/// path are disjoint and each sorted: they are merged through a bit row over the objects when
/// that is short next to the ids (a scan of words), else sorted.
void decode_cell(const vc_pvs* pvs, uint32_t cell, std::vector<uint32_t>& out) {
  out.clear();
  thread_local std::vector<uint32_t> part;
  for (int32_t n = static_cast<int32_t>(cell); n >= 0; n = pvs->node_parent[n]) {
    const uint32_t bit = pvs->node_bit[n];
    viewcells::id_lists::BitReader r(pvs->coded.data() + bit / 8, pvs->coded.size() - bit / 8);
    r.get(static_cast<int>(bit % 8));
    viewcells::id_lists::get_list(r, pvs->object_count, part);  // checked when the handle was opened
    out.insert(out.end(), part.begin(), part.end());
  }
  const size_t words = (static_cast<size_t>(pvs->object_count) + 63) / 64;
  if (words > 4 * out.size()) {
    std::sort(out.begin(), out.end());
    return;
  }
  thread_local std::vector<uint64_t> row;
  row.assign(words, 0);
  for (uint32_t o : out) row[o >> 6] |= uint64_t{1} << (o & 63);
  size_t k = 0;
  for (size_t w = 0; w < words; ++w)
    for (uint64_t bits = row[w]; bits; bits &= bits - 1)
      out[k++] = static_cast<uint32_t>(64 * w + static_cast<size_t>(__builtin_ctzll(bits)));
}

}  // namespace

int vc_pvs_open(const char* path, vc_pvs** out, char* error, size_t error_size) {
  return open_handle(path, nullptr, 0, out, error, error_size, false);
}

int vc_pvs_open_compact(const char* path, vc_pvs** out, char* error, size_t error_size) {
  return open_handle(path, nullptr, 0, out, error, error_size, true);
}

int vc_pvs_open_memory(const void* bytes, size_t size, int compact, vc_pvs** out, char* error, size_t error_size) {
  return open_handle(nullptr, bytes, size, out, error, error_size, compact != 0);
}

void vc_pvs_close(vc_pvs* pvs) { delete pvs; }

int vc_pvs_is_compact(const vc_pvs* pvs) { return pvs && pvs->compact ? 1 : 0; }

size_t vc_pvs_list_bytes(const vc_pvs* pvs) {
  if (!pvs) return 0;
  return pvs->compact ? pvs->coded.size() + pvs->node_bit.size() * sizeof(uint32_t) +
                            pvs->node_parent.size() * sizeof(int32_t)
                      : pvs->offsets.size() * sizeof(uint64_t) + pvs->ids.size() * sizeof(uint32_t);
}

uint32_t vc_pvs_cell_count(const vc_pvs* pvs) { return pvs ? pvs->cell_count : 0; }
uint32_t vc_pvs_object_count(const vc_pvs* pvs) { return pvs ? pvs->object_count : 0; }
size_t vc_pvs_row_bytes(const vc_pvs* pvs) { return pvs ? (static_cast<size_t>(pvs->object_count) + 7) / 8 : 0; }
uint64_t vc_pvs_scene_fingerprint(const vc_pvs* pvs) { return pvs ? pvs->fingerprint : 0; }
const char* vc_pvs_rule(const vc_pvs* pvs) { return pvs ? pvs->rule.c_str() : ""; }

void vc_pvs_view_box(const vc_pvs* pvs, double lo[3], double hi[3]) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 3; ++k) {
    if (lo) lo[k] = pvs ? pvs->lo[k] : none;
    if (hi) hi[k] = pvs ? pvs->hi[k] : none;
  }
}

const char* vc_pvs_object_name(const vc_pvs* pvs, uint32_t object) {
  return pvs && object < pvs->names.size() ? pvs->names[object].c_str() : "";
}

size_t vc_pvs_memory_bytes(const vc_pvs* pvs) {
  if (!pvs) return 0;
  size_t n = sizeof(vc_pvs) + pvs->rule.capacity();
  for (const std::string& s : pvs->names) n += sizeof(s) + s.capacity();
  return n + pvs->nodes.capacity() * sizeof(Node) + pvs->planes.capacity() * sizeof(GeneralPlane) +
         pvs->grid_start.capacity() * sizeof(uint32_t) + pvs->offsets.capacity() * sizeof(uint64_t) +
         pvs->ids.capacity() * sizeof(uint32_t) + pvs->coded.capacity() +
         pvs->node_bit.capacity() * sizeof(uint32_t) + pvs->node_parent.capacity() * sizeof(int32_t);
}

namespace {

/// The leaf holding p, or null outside the view box (NaN coordinates included).
inline const Node* leaf_at(const vc_pvs* pvs, double x, double y, double z) {
  if (!pvs) return nullptr;
  const Vec p{{x, y, z}};
  size_t cell = 0, stride = 1;
  for (int k = 0; k < 3; ++k) {
    if (!(p.v[k] >= pvs->lo[k] && p.v[k] <= pvs->hi[k])) return nullptr;  // NaN fails too
    // Clamped in double before the conversion: an index of inf or NaN never reaches an int.
    const double t = (p.v[k] - pvs->lo[k]) * pvs->grid_scale[k];
    const int i = t > 0 ? static_cast<int>(std::min(t, static_cast<double>(pvs->grid_n[k] - 1))) : 0;
    cell += stride * static_cast<size_t>(i);
    stride *= static_cast<size_t>(pvs->grid_n[k]);
  }
  const Node* nodes = pvs->nodes.data();
  const Node* n = nodes + pvs->grid_start[cell];
  while (n->right) {
    const uint32_t axis = n->meta >> 30;
    const bool positive = axis < 3 ? p.v[axis] > n->offset : orientation(pvs->planes[n->meta & kIndex], p) > 0;
    n = positive ? nodes + n->right : n + 1;
  }
  return n;
}

}  // namespace

int32_t vc_pvs_locate(const vc_pvs* pvs, double x, double y, double z) {
  const Node* n = leaf_at(pvs, x, y, z);
  return n ? static_cast<int32_t>(n->meta) : -1;
}

int32_t vc_pvs_locate_objects(const vc_pvs* pvs, double x, double y, double z, const uint32_t** objects,
                              size_t* count) {
  const Node* n = leaf_at(pvs, x, y, z);
  const bool listed = n && !pvs->compact;  // n is null for a null handle
  if (objects) *objects = listed ? pvs->ids.data() + n->list[0] : nullptr;
  if (count) *count = listed ? n->list[1] : 0;
  return n ? static_cast<int32_t>(n->meta) : -1;
}

size_t vc_pvs_cell_objects(const vc_pvs* pvs, int32_t cell, const uint32_t** objects) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count || pvs->compact) {
    if (objects) *objects = nullptr;
    return 0;
  }
  const uint64_t first = pvs->offsets[cell], last = pvs->offsets[cell + 1];
  if (objects) *objects = pvs->ids.data() + first;
  return static_cast<size_t>(last - first);
}

size_t vc_pvs_cell_objects_copy(const vc_pvs* pvs, int32_t cell, uint32_t* objects, size_t capacity) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count) return 0;
  if (!pvs->compact) {
    const uint64_t first = pvs->offsets[cell], count = pvs->offsets[cell + 1] - first;
    if (objects) std::copy_n(pvs->ids.data() + first, std::min<uint64_t>(count, capacity), objects);
    return static_cast<size_t>(count);
  }
  thread_local std::vector<uint32_t> ids;
  decode_cell(pvs, static_cast<uint32_t>(cell), ids);
  if (objects) std::copy_n(ids.data(), std::min(ids.size(), capacity), objects);
  return ids.size();
}

int vc_pvs_cell_bits(const vc_pvs* pvs, int32_t cell, uint8_t* row, size_t row_bytes) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count || !row || row_bytes < vc_pvs_row_bytes(pvs))
    return -1;
  std::memset(row, 0, row_bytes);
  if (pvs->compact) {
    thread_local std::vector<uint32_t> ids;
    decode_cell(pvs, static_cast<uint32_t>(cell), ids);
    for (uint32_t o : ids) row[o >> 3] = static_cast<uint8_t>(row[o >> 3] | (1u << (o & 7)));
    return 0;
  }
  for (uint64_t i = pvs->offsets[cell]; i < pvs->offsets[cell + 1]; ++i)
    row[pvs->ids[i] >> 3] = static_cast<uint8_t>(row[pvs->ids[i] >> 3] | (1u << (pvs->ids[i] & 7)));
  return 0;
}

int vc_pvs_cell_sees(const vc_pvs* pvs, int32_t cell, uint32_t object) {
  if (!pvs || cell < 0 || static_cast<uint32_t>(cell) >= pvs->cell_count) return 0;
  if (pvs->compact) {
    thread_local std::vector<uint32_t> ids;
    decode_cell(pvs, static_cast<uint32_t>(cell), ids);
    return std::binary_search(ids.begin(), ids.end(), object) ? 1 : 0;
  }
  const uint32_t* first = pvs->ids.data() + pvs->offsets[cell];
  const uint32_t* last = pvs->ids.data() + pvs->offsets[cell + 1];
  return std::binary_search(first, last, object) ? 1 : 0;
}

}  // extern "C"
