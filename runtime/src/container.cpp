// The .pvs container (container.h), read with zstd alone.
#include "container.h"

#include <zstd.h>

#include <fstream>
#include <iterator>
#include <sys/stat.h>

namespace viewcells::runtime_detail {

namespace {

uint64_t fnv1a64(const std::string& bytes) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace

std::string read_container(const std::string& path, uint32_t& version) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) throw FileError("no such file");
  if (!S_ISREG(st.st_mode)) throw FileError("not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open file");
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (file.size() < 32) throw FileError("not a .pvs file (too short)");
  if (std::memcmp(file.data(), "VPVS", 4) != 0) throw FileError("not a .pvs file (wrong magic)");
  Reader r(file);
  r.get<uint32_t>();
  const uint32_t tagged = r.get<uint32_t>();
  if (tagged >> 24) throw FileError("corrupt file: malformed version field");
  version = tagged & 0xffff;
  if (version != 1 && version != 2)
    throw FileError("format version " + std::to_string(version) + " is not supported (this reader reads 1 and 2)");
  const uint64_t raw_size = r.get<uint64_t>(), checksum = r.get<uint64_t>(), csize = r.get<uint64_t>();
  if (csize != file.size() - 32) throw FileError("corrupt file: compressed size does not match (truncated?)");
  if (ZSTD_getFrameContentSize(file.data() + 32, csize) != raw_size)
    throw FileError("corrupt file: compressed frame does not match header");
  if (raw_size > 65536 * (csize + 64)) throw FileError("corrupt file: impossible decompressed size");
  std::string payload(raw_size, '\0');
  const size_t got = ZSTD_decompress(payload.data(), raw_size, file.data() + 32, csize);
  if (ZSTD_isError(got) || got != raw_size) throw FileError("corrupt file: decompression failed");
  if (fnv1a64(payload) != checksum) throw FileError("corrupt file: checksum mismatch");
  return payload;
}

}  // namespace viewcells::runtime_detail
