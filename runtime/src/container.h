#pragma once
// The .pvs container as the runtime reads it (the format itself: viewcells/format/container.h),
// and bounds-checked reads of the payload.
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace viewcells::runtime_detail {

class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bounds-checked little-endian reads of a payload.
class Reader {
 public:
  explicit Reader(const std::string& data) : data_(data) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string get_string() {
    const uint64_t n = get<uint64_t>();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  template <class T>
  std::vector<T> get_array(uint64_t max_count) {
    const uint64_t n = get<uint64_t>();
    if (n > max_count) throw FileError("corrupt file: an array larger than the file");
    need(n * sizeof(T));
    std::vector<T> v(n);
    if (n) std::memcpy(v.data(), data_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return v;
  }
  uint32_t get_varint() {
    uint32_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      const uint8_t b = get<uint8_t>();
      v |= static_cast<uint32_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    throw FileError("corrupt file: malformed varint");
  }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  void need(uint64_t n) const {
    if (n > data_.size() - pos_) throw FileError("corrupt file: payload ends early");
  }
  const std::string& data_;
  size_t pos_ = 0;
};

/// The payload of the .pvs file at `path`, checked (format/container.h), and its version.
std::string read_container(const std::string& path, uint32_t& version);
/// The payload of a .pvs file's bytes `file`, checked, and its version.
std::string decode_container(const std::string& file, uint32_t& version);

}  // namespace viewcells::runtime_detail
