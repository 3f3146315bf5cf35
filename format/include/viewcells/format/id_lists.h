#pragma once
// The coding of the .pvs file's object lists (format version 2), shared by the toolkit that
// writes them (libviewcells/src/pvs/pvs.cpp) and the engines' reader (load.cpp, c_api.cpp).
//
// Every list of the hierarchy is a sorted set of distinct object ids below `universe` (the
// file's object count). The lists follow one another in one bit stream, least significant
// bit first within each byte, the last byte padded with zero bits:
//   - the list's size n as the Elias gamma code of n + 1;
//   - its ids by binary interpolative coding (Moffat and Stuiver, "Binary interpolative
//     coding for effective index compression", Information Retrieval 3, 2000): the middle id
//     in truncated binary within the range the ids around it leave it, then each half the
//     same way within its narrower range. A run of consecutive ids that fills its range costs
//     no bits, and a sparse list costs about log2(universe / n) + 1.5 bits an id.
// Version 1 stored each list as LEB128 varints of the differences (about 8 bits an id).
//
// Decoding cannot produce an id out of range or out of order whatever the bytes: a truncated
// binary value never leaves its range. A stream that ends early, a size beyond the universe
// or a gamma code longer than 32 zero bits makes the reader report a malformed stream.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace viewcells::id_lists {

class BitWriter {
 public:
  /// Appends the low `bits` bits of v (bits <= 56).
  void put(uint64_t v, int bits) {
    acc_ |= v << filled_;
    filled_ += bits;
    while (filled_ >= 8) {
      bytes_.push_back(static_cast<char>(acc_ & 0xff));
      acc_ >>= 8;
      filled_ -= 8;
    }
  }
  uint64_t bits() const { return 8 * bytes_.size() + static_cast<uint64_t>(filled_); }
  /// The bytes, the last one padded with zero bits.
  std::string finish() {
    if (filled_ > 0) bytes_.push_back(static_cast<char>(acc_ & 0xff));
    acc_ = 0;
    filled_ = 0;
    return std::move(bytes_);
  }

 private:
  std::string bytes_;
  uint64_t acc_ = 0;
  int filled_ = 0;
};

class BitReader {
 public:
  BitReader(const char* data, size_t size)
      : begin_(reinterpret_cast<const unsigned char*>(data)), p_(begin_), end_(p_ + size) {}
  /// The next `bits` bits (bits <= 56); zeros and `overrun()` once the stream has ended.
  uint64_t get(int bits) {
    while (filled_ < bits) {
      if (p_ == end_) {
        overrun_ = true;
        return 0;
      }
      acc_ |= static_cast<uint64_t>(*p_++) << filled_;
      filled_ += 8;
    }
    const uint64_t v = bits ? acc_ & ((uint64_t{1} << bits) - 1) : 0;
    acc_ = bits ? acc_ >> bits : acc_;
    filled_ -= bits;
    return v;
  }
  bool overrun() const { return overrun_; }
  /// Bits read so far.
  uint64_t position() const { return 8 * static_cast<uint64_t>(p_ - begin_) - static_cast<uint64_t>(filled_); }
  /// True when every byte was read and the padding bits are zero.
  bool at_end() const { return !overrun_ && p_ == end_ && acc_ == 0; }

 private:
  const unsigned char* begin_;
  const unsigned char* p_;
  const unsigned char* end_;
  uint64_t acc_ = 0;
  int filled_ = 0;
  bool overrun_ = false;
};

namespace detail {

inline int floor_log2(uint64_t v) {  // v >= 1
  int k = 0;
  while (v >> (k + 1)) ++k;
  return k;
}

/// x in [0, r): floor(log2 r) bits for the first 2^(k+1) - r values, one more for the rest.
inline void put_truncated(BitWriter& w, uint64_t x, uint64_t r) {
  if (r <= 1) return;
  const int k = floor_log2(r);
  const uint64_t u = (uint64_t{1} << (k + 1)) - r;
  if (x < u) {
    w.put(x, k);
  } else {
    const uint64_t y = x + u;  // k + 1 bits, the high k first so that the reader can decide
    w.put(y >> 1, k);
    w.put(y & 1, 1);
  }
}

inline uint64_t get_truncated(BitReader& r, uint64_t range) {
  if (range <= 1) return 0;
  const int k = floor_log2(range);
  const uint64_t u = (uint64_t{1} << (k + 1)) - range;
  const uint64_t t = r.get(k);
  if (t < u) return t;
  return ((t << 1) | r.get(1)) - u;
}

/// ids[0..n) sorted, distinct, within [lo, hi], with hi - lo + 1 >= n.
inline void put_range(BitWriter& w, const uint32_t* ids, size_t n, uint64_t lo, uint64_t hi) {
  while (n > 0 && hi - lo + 1 > n) {
    const size_t m = n / 2;
    const uint64_t v = ids[m];
    put_truncated(w, v - (lo + m), hi - lo + 2 - n);  // v within [lo + m, hi - (n - 1 - m)]
    put_range(w, ids, m, lo, v - 1);                 // m > 0 implies v > lo
    ids += m + 1;
    n -= m + 1;
    lo = v + 1;
  }
  // n == 0, or the ids fill [lo, hi]: nothing to write.
}

inline void get_range(BitReader& r, uint32_t* ids, size_t n, uint64_t lo, uint64_t hi) {
  while (n > 0 && hi - lo + 1 > n) {
    const size_t m = n / 2;
    const uint64_t v = lo + m + get_truncated(r, hi - lo + 2 - n);
    ids[m] = static_cast<uint32_t>(v);
    get_range(r, ids, m, lo, v - 1);
    ids += m + 1;
    n -= m + 1;
    lo = v + 1;
  }
  for (size_t i = 0; i < n; ++i) ids[i] = static_cast<uint32_t>(lo + i);
}

}  // namespace detail

/// Appends one list: `ids` sorted, distinct and below `universe` (the caller checks).
inline void put_list(BitWriter& w, const uint32_t* ids, size_t n, uint32_t universe) {
  const uint64_t g = n + 1;  // Elias gamma: floor(log2 g) zeros, then g from its top bit down
  const int k = detail::floor_log2(g);
  w.put(0, k);
  for (int b = k; b >= 0; --b) w.put((g >> b) & 1, 1);
  if (n) detail::put_range(w, ids, n, 0, uint64_t{universe} - 1);
}

/// Reads one list into `out`; false when the stream is malformed (see the file comment).
inline bool get_list(BitReader& r, uint32_t universe, std::vector<uint32_t>& out) {
  int k = 0;
  while (r.get(1) == 0) {
    if (r.overrun() || ++k > 32) return false;
  }
  uint64_t g = 1;
  for (int b = 0; b < k; ++b) g = (g << 1) | r.get(1);
  if (r.overrun() || g - 1 > universe) return false;
  out.resize(static_cast<size_t>(g - 1));
  if (!out.empty()) detail::get_range(r, out.data(), out.size(), 0, uint64_t{universe} - 1);
  return !r.overrun();
}

/// The bytes of `lists` coded one after another.
inline std::string encode(const std::vector<std::vector<uint32_t>>& lists, uint32_t universe) {
  BitWriter w;
  for (const auto& l : lists) put_list(w, l.data(), l.size(), universe);
  return w.finish();
}

/// The size in bytes of encode(lists, universe), computed the same way.
inline uint64_t encoded_bytes(const std::vector<std::vector<uint32_t>>& lists, uint32_t universe) {
  return encode(lists, universe).size();
}

}  // namespace viewcells::id_lists
