#pragma once
// C++17 wrapper over the viewcells runtime's C API (runtime.h): an owning handle that throws
// std::runtime_error when a file cannot be opened.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "viewcells/runtime.h"

namespace viewcells::runtime {

/// A view of one cell's visible objects: sorted ids, owned by the PvsFile.
struct ObjectList {
  const uint32_t* data = nullptr;
  size_t size = 0;
  const uint32_t* begin() const { return data; }
  const uint32_t* end() const { return data + size; }
  bool empty() const { return size == 0; }
};

class PvsFile {
 public:
  /// Opens the file; `compact` keeps its lists coded (vc_pvs_open_compact): read them with
  /// objects_copy, bits or sees.
  explicit PvsFile(const std::string& path, bool compact = false) {
    char error[512];
    const int code = compact ? vc_pvs_open_compact(path.c_str(), &handle_, error, sizeof error)
                             : vc_pvs_open(path.c_str(), &handle_, error, sizeof error);
    if (code != 0) throw std::runtime_error(error);
  }
  ~PvsFile() { vc_pvs_close(handle_); }
  PvsFile(PvsFile&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)) {}
  PvsFile& operator=(PvsFile&& o) noexcept {
    std::swap(handle_, o.handle_);
    return *this;
  }
  PvsFile(const PvsFile&) = delete;
  PvsFile& operator=(const PvsFile&) = delete;

  uint32_t cell_count() const { return vc_pvs_cell_count(handle_); }
  uint32_t object_count() const { return vc_pvs_object_count(handle_); }
  size_t row_bytes() const { return vc_pvs_row_bytes(handle_); }
  uint64_t scene_fingerprint() const { return vc_pvs_scene_fingerprint(handle_); }
  std::string rule() const { return vc_pvs_rule(handle_); }
  std::string object_name(uint32_t object) const { return vc_pvs_object_name(handle_, object); }
  size_t memory_bytes() const { return vc_pvs_memory_bytes(handle_); }
  size_t list_bytes() const { return vc_pvs_list_bytes(handle_); }
  bool compact() const { return vc_pvs_is_compact(handle_) != 0; }

  /// The view cell containing the point, or -1 outside the view space.
  int32_t locate(double x, double y, double z) const { return vc_pvs_locate(handle_, x, y, z); }
  /// The visible objects of the cell containing the point (empty outside the view space).
  ObjectList objects_at(double x, double y, double z, int32_t* cell = nullptr) const {
    ObjectList l;
    const int32_t c = vc_pvs_locate_objects(handle_, x, y, z, &l.data, &l.size);
    if (cell) *cell = c;
    return l;
  }
  /// The cell's visible objects (empty for a cell out of range).
  ObjectList objects(int32_t cell) const {
    ObjectList l;
    l.size = vc_pvs_cell_objects(handle_, cell, &l.data);
    return l;
  }
  /// The cell's visible objects, copied (any handle; empty for a cell out of range).
  std::vector<uint32_t> objects_copy(int32_t cell) const {
    std::vector<uint32_t> ids(object_count());  // a cell sees at most every object: one pass
    ids.resize(vc_pvs_cell_objects_copy(handle_, cell, ids.data(), ids.size()));
    return ids;
  }
  /// The cell's bit row, row_bytes() long; throws std::out_of_range for a cell out of range.
  std::vector<uint8_t> bits(int32_t cell) const {
    std::vector<uint8_t> row(row_bytes());
    if (vc_pvs_cell_bits(handle_, cell, row.data(), row.size()) != 0) throw std::out_of_range("no such view cell");
    return row;
  }
  bool sees(int32_t cell, uint32_t object) const { return vc_pvs_cell_sees(handle_, cell, object) != 0; }
  const vc_pvs* handle() const { return handle_; }

 private:
  vc_pvs* handle_ = nullptr;
};

}  // namespace viewcells::runtime
