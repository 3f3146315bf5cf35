#pragma once
/// The PVS of every view cell at once as bit rows over the objects: what global visibility
/// sampling fills (the AGVS solver) and the visibility filter reads. Sorted lists come out of it;
/// the compressed hierarchy of a .pvs file is pvs/pvs.h.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace viewcells {

class ByteWriter;
class ByteReader;

/// The PVS of every cell as a bit row over the objects; entries are only ever added.
class GlobalPvs {
 public:
  GlobalPvs() = default;
  GlobalPvs(uint32_t cells, uint32_t objects);
  /// The table of per-cell object lists (ids < objects).
  static GlobalPvs from_lists(uint32_t objects, const std::vector<std::vector<uint32_t>>& lists);
  uint32_t cell_count() const { return cells_; }
  uint32_t object_count() const { return objects_; }
  bool contains(uint32_t cell, uint32_t object) const {
    return (bits_[size_t(cell) * words_ + object / 64] >> (object % 64)) & 1;
  }
  /// Adds the entry; true when it is new.
  bool insert(uint32_t cell, uint32_t object);
  /// insert() that leaves the table's total entries to add_entries(): threads may insert into
  /// different cells at once.
  bool insert_in_row(uint32_t cell, uint32_t object) {
    uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
    const uint64_t bit = uint64_t{1} << (object % 64);
    if (w & bit) return false;
    w |= bit;
    ++sizes_[cell];
    return true;
  }
  void add_entries(uint64_t n) { entries_ += n; }
  /// Removes the entry (dynamic edits only); true when it was there.
  bool erase(uint32_t cell, uint32_t object);
  uint32_t size(uint32_t cell) const { return sizes_[cell]; }
  uint64_t entries() const { return entries_; }
  /// Entries that `other` (of the same shape) has too.
  uint64_t common_entries(const GlobalPvs& other) const;
  std::vector<uint32_t> list(uint32_t cell) const;  ///< sorted object ids
  bool operator==(const GlobalPvs& o) const { return cells_ == o.cells_ && objects_ == o.objects_ && bits_ == o.bits_; }
  /// The bit rows (cell after cell, words_per_row() words each), for combining tables held by
  /// several processes; after changing them, call recount().
  std::vector<uint64_t>& raw_bits() { return bits_; }
  size_t words_per_row() const { return words_; }
  void recount();
  void save(ByteWriter& w) const;
  /// Reads what save() wrote; Error unless it has `cells` rows over `objects` objects.
  static GlobalPvs load(ByteReader& r, uint32_t cells, uint32_t objects);

 private:
  uint32_t cells_ = 0, objects_ = 0;
  size_t words_ = 0;
  std::vector<uint64_t> bits_;
  std::vector<uint32_t> sizes_;
  uint64_t entries_ = 0;
};

}  // namespace viewcells
