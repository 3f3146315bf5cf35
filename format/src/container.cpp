// The container (container.h): header, zstd frame, checksum.
#include "viewcells/format/container.h"

#include <zstd.h>

#include <cstring>
#include <memory>

namespace viewcells::format {

namespace {

template <class T>
void put(std::string& out, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <class T>
T get(const std::string& file, size_t at) {
  T v;
  std::memcpy(&v, file.data() + at, sizeof(T));
  return v;
}

}  // namespace

uint64_t fnv1a64(const std::string& bytes) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string encode_container(const char* magic, uint32_t tagged_version, const std::string& payload) {
  // Compressed into a buffer left uninitialised (the bound is about the payload's size, and
  // zeroing it cost a pass over that much memory), then copied once behind the header.
  const size_t bound = ZSTD_compressBound(payload.size());
  const std::unique_ptr<char[]> compressed(new char[bound]);
  const size_t csize = ZSTD_compress(compressed.get(), bound, payload.data(), payload.size(), /*level=*/1);
  if (ZSTD_isError(csize)) throw FormatError(std::string("zstd: ") + ZSTD_getErrorName(csize));
  std::string file;
  file.reserve(kContainerHeaderBytes + csize);
  file.append(magic, 4);
  put<uint32_t>(file, tagged_version);
  put<uint64_t>(file, payload.size());
  put<uint64_t>(file, fnv1a64(payload));
  put<uint64_t>(file, csize);
  file.append(compressed.get(), csize);
  return file;
}

ContainerHeader read_container_header(const std::string& file, const char* magic, const std::string& kind) {
  if (file.size() < kContainerHeaderBytes) throw FormatError("not a " + kind + " file (too short)");
  if (std::memcmp(file.data(), magic, 4) != 0) throw FormatError("not a " + kind + " file (wrong magic)");
  ContainerHeader h;
  h.tagged_version = get<uint32_t>(file, 4);
  if (h.tagged_version >> 24) throw FormatError("corrupt file: malformed version field");
  h.payload_size = get<uint64_t>(file, 8);
  h.checksum = get<uint64_t>(file, 16);
  h.compressed_size = get<uint64_t>(file, 24);
  return h;
}

std::string decode_container_payload(const std::string& file, const ContainerHeader& h) {
  const uint64_t csize = h.compressed_size, raw_size = h.payload_size;
  if (csize != file.size() - kContainerHeaderBytes)
    throw FormatError("corrupt file: expected " + std::to_string(csize) + " compressed bytes, found " +
                      std::to_string(file.size() - kContainerHeaderBytes) + " (truncated?)");
  const char* frame = file.data() + kContainerHeaderBytes;
  if (ZSTD_getFrameContentSize(frame, csize) != raw_size)
    throw FormatError("corrupt file: compressed frame does not match header");
  // zstd expands at most about 32,768-fold (a 128 KiB run-length block in 4 bytes): a larger
  // claim is corrupt, and is refused before it is allocated.
  if (raw_size > 65536 * (csize + 64))
    throw FormatError("corrupt file: " + std::to_string(raw_size) + " bytes claimed from " + std::to_string(csize) +
                      " compressed");
  std::string payload(raw_size, '\0');
  const size_t got = ZSTD_decompress(payload.data(), raw_size, frame, csize);
  if (ZSTD_isError(got) || got != raw_size) throw FormatError("corrupt file: decompression failed");
  if (fnv1a64(payload) != h.checksum) throw FormatError("corrupt file: checksum mismatch");
  return payload;
}

}  // namespace viewcells::format
