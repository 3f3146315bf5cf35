#pragma once
/// Versioned, checksummed binary containers for the toolkit's own files (.vseg, later .vcells
/// and .pvs). Layout: magic (4 bytes), format version (u32), payload size (u64), FNV-1a 64
/// checksum of the payload (u64), compressed size (u64), then the zstd-compressed payload.
/// Little-endian. Reading rejects wrong magic, newer versions, truncation and bit flips.
#include <cstdint>
#include <cstring>
#include <istream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "viewcells/core/error.h"

namespace viewcells {

/// Appends plain values and arrays to a byte buffer.
class ByteWriter {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&v);
    data_.append(p, sizeof(T));
  }
  template <class T, class A>
  void put_array(const std::vector<T, A>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<uint64_t>(v.size());
    data_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void put_string(const std::string& s) {
    put<uint64_t>(s.size());
    data_.append(s);
  }
  /// Room for `bytes` in all, so that a large payload is not copied as it grows.
  void reserve(size_t bytes) { data_.reserve(bytes); }
  const std::string& data() const { return data_; }
  /// The bytes, moved out (the writer is empty afterwards).
  std::string take() { return std::move(data_); }

 private:
  std::string data_;
};

/// Reads what ByteWriter wrote; every read is bounds-checked and throws Error naming the file.
class ByteReader {
 public:
  ByteReader(const std::string& data, std::string file) : data_(data), file_(std::move(file)) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  /// max_count guards against absurd sizes in a corrupt file before allocating.
  template <class T, class A>
  void get_array(std::vector<T, A>& v, uint64_t max_count) {
    static_assert(std::is_trivially_copyable_v<T>);
    const uint64_t n = get<uint64_t>();
    if (n > max_count) fail("array of " + std::to_string(n) + " elements exceeds " + std::to_string(max_count));
    need(n * sizeof(T));
    v.resize(n);
    if (n) std::memcpy(v.data(), data_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
  }
  template <class T>
  std::vector<T> get_array(uint64_t max_count) {
    std::vector<T> v;
    get_array(v, max_count);
    return v;
  }
  std::string get_string() {
    const uint64_t n = get<uint64_t>();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  bool at_end() const { return pos_ == data_.size(); }
  size_t position() const { return pos_; }
  /// Back to an earlier position (to read a part once what it depends on is validated).
  void seek(size_t pos) {
    if (pos > data_.size()) fail("seek past the end");
    pos_ = pos;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(file_, 0, "corrupt file: " + what);
  }

 private:
  void need(uint64_t n) const {
    if (n > data_.size() - pos_) fail("payload ends early");
  }
  const std::string& data_;
  std::string file_;
  size_t pos_ = 0;
};

/// Writes payload into `path` atomically (temporary file + rename). The header records the
/// format version and the Embree ISA this process casts with (embree_isa()).
void write_container(const std::string& path, const char (&magic)[5], uint32_t version,
                     const std::string& payload);
/// The bytes write_container would write (for measuring a file without writing it).
std::string container_image(const char (&magic)[5], uint32_t version, const std::string& payload);
/// Reads and verifies a container; returns the payload and sets `version` (and `isa`, the
/// Embree ISA of the process that wrote it, when given). Throws Error for a missing or
/// non-regular file, wrong magic, a version above max_version, or corruption.
std::string read_container(const std::string& path, const char (&magic)[5], uint32_t max_version,
                           uint32_t& version, std::string* isa = nullptr);

/// FNV-1a 64-bit hash of a byte string.
uint64_t fnv1a64(const std::string& bytes);

/// The rest of stream `in`, read in blocks (a character iterator took about 6 ns a byte:
/// 0.45 s for a 72 MB hierarchy); throws Error naming `name` on a read error.
std::string read_all(std::istream& in, const std::string& name);
/// The whole file at `path`; throws Error naming it when it cannot be opened or read.
std::string read_file_bytes(const std::string& path);

/// Writes `text` to `path` atomically (a temporary file, then install_file); throws Error on
/// failure, or when `path` exists as something other than a regular file.
void write_text_file(const std::string& path, const std::string& text);

/// Throws Error when `path` exists and is not a regular file (a directory, device, FIFO or
/// symbolic link): outputs replace files, and must not replace those.
void check_output_target(const std::string& path);
/// The temporary file a writer of `path` writes first (beside it, named by the process and a
/// counter).
std::string temporary_for(const std::string& path);
/// Moves the finished temporary `tmp` onto `path`: at once, or, while an OutputBatch is open,
/// when it commits.
void install_file(const std::string& tmp, const std::string& path);
/// Where the content of `path` is now: its staged temporary while a batch holds it, else path.
std::string staged_path(const std::string& path);

/// While alive, files are installed at once even when an OutputBatch is open: for a work
/// directory's checkpoints, which must survive a command that fails or is cut off later.
class UnbatchedWrites {
 public:
  UnbatchedWrites();
  ~UnbatchedWrites();
  UnbatchedWrites(const UnbatchedWrites&) = delete;
  UnbatchedWrites& operator=(const UnbatchedWrites&) = delete;

 private:
  std::vector<std::pair<std::string, std::string>>* saved_;
};

/// All outputs of one command: while it is open, files written through write_text_file,
/// write_container or install_file stay temporary and are renamed onto their targets only by
/// commit(). Destroyed without commit (the command failed), it removes them, so that a failing
/// command leaves every earlier file as it was. One at a time per thread: it holds the files
/// written on the thread that opened it (a bake writes its outputs on its calling thread).
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  void commit();

 private:
  std::vector<std::pair<std::string, std::string>> staged_;
};

}  // namespace viewcells
