/// Every view cell's PVS at once as bit rows over the objects: what global visibility sampling
/// fills.
#include "viewcells/pvs/global_pvs.h"

#include <algorithm>
#include <bit>

#include "viewcells/core/binary_file.h"
#include "viewcells/core/error.h"

namespace viewcells {

GlobalPvs::GlobalPvs(uint32_t cells, uint32_t objects)
    : cells_(cells), objects_(objects), words_((objects + 63) / 64), bits_(size_t(cells) * words_, 0), sizes_(cells, 0) {}

GlobalPvs GlobalPvs::from_lists(uint32_t objects, const std::vector<std::vector<uint32_t>>& lists) {
  GlobalPvs p(static_cast<uint32_t>(lists.size()), objects);
  for (uint32_t c = 0; c < lists.size(); ++c)
    for (uint32_t o : lists[c]) p.insert(c, o);
  return p;
}

bool GlobalPvs::insert(uint32_t cell, uint32_t object) {
  if (!insert_in_row(cell, object)) return false;
  ++entries_;
  return true;
}

void GlobalPvs::recount() {
  entries_ = 0;
  for (uint32_t c = 0; c < cells_; ++c) {
    uint32_t n = 0;
    for (size_t k = 0; k < words_; ++k) n += static_cast<uint32_t>(__builtin_popcountll(bits_[size_t(c) * words_ + k]));
    sizes_[c] = n;
    entries_ += n;
  }
}

bool GlobalPvs::erase(uint32_t cell, uint32_t object) {
  uint64_t& w = bits_[size_t(cell) * words_ + object / 64];
  const uint64_t bit = uint64_t{1} << (object % 64);
  if (!(w & bit)) return false;
  w &= ~bit;
  --sizes_[cell];
  --entries_;
  return true;
}

uint64_t GlobalPvs::common_entries(const GlobalPvs& other) const {
  if (other.cells_ != cells_ || other.objects_ != objects_) throw Error("PVS tables of different shapes");
  uint64_t n = 0;
  for (size_t w = 0; w < bits_.size(); ++w) n += static_cast<uint64_t>(__builtin_popcountll(bits_[w] & other.bits_[w]));
  return n;
}

std::vector<uint32_t> GlobalPvs::list(uint32_t cell) const {
  std::vector<uint32_t> out;
  out.reserve(sizes_[cell]);
  for (size_t w = 0; w < words_; ++w)
    for (uint64_t bits = bits_[size_t(cell) * words_ + w]; bits; bits &= bits - 1)
      out.push_back(static_cast<uint32_t>(w * 64 + __builtin_ctzll(bits)));
  return out;
}

void GlobalPvs::save(ByteWriter& w) const {
  w.put(cells_);
  w.put(objects_);
  w.put_array(bits_);
}

GlobalPvs GlobalPvs::load(ByteReader& r, uint32_t cells, uint32_t objects) {
  const uint32_t file_cells = r.get<uint32_t>();
  const uint32_t file_objects = r.get<uint32_t>();
  if (file_cells != cells || file_objects != objects) r.fail("the PVS table does not match the cells and objects");
  GlobalPvs p(cells, objects);
  std::vector<uint64_t> bits;
  r.get_array(bits, p.bits_.size());
  if (bits.size() != p.bits_.size()) r.fail("PVS rows of the wrong size");
  p.bits_ = std::move(bits);
  for (uint32_t c = 0; c < p.cells_; ++c) {
    uint32_t n = 0;
    for (size_t w = 0; w < p.words_; ++w) n += static_cast<uint32_t>(__builtin_popcountll(p.bits_[c * p.words_ + w]));
    if (p.words_ && p.objects_ % 64 && (p.bits_[c * p.words_ + p.words_ - 1] >> (p.objects_ % 64)))
      r.fail("PVS names objects that do not exist");
    p.sizes_[c] = n;
    p.entries_ += n;
  }
  return p;
}

}  // namespace viewcells
