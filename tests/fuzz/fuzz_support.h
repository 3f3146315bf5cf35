#pragma once
// Shared by the libFuzzer targets (scripts/fuzz.sh): a per-process scratch file, and the
// container the toolkit's own formats live in, so that inputs reach the payload parsers past
// the checksum (a fuzzer cannot forge FNV-1a).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "viewcells/core/error.h"
#include "viewcells/io/binary_file.h"

namespace viewcells::fuzz {

/// A scratch path in /dev/shm (or /tmp) with the given extension, one per process.
inline std::string scratch(const std::string& ext) {
  const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  return std::string(dir) + "/viewcells_fuzz_" + std::to_string(getpid()) + ext;
}

inline void write_bytes(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                                 static_cast<std::streamsize>(size));
}

/// The input as the payload of a valid container: the first byte picks the format version
/// (1..max_version), the rest is the payload.
inline std::string container_file(const uint8_t* data, size_t size, const char (&magic)[5], uint32_t max_version,
                                  const std::string& ext) {
  const std::string path = scratch(ext);
  const uint32_t version = size ? 1 + data[0] % max_version : 1;
  const std::string payload(reinterpret_cast<const char*>(data) + (size ? 1 : 0), size ? size - 1 : 0);
  write_container(path, magic, version, payload);
  return path;
}

}  // namespace viewcells::fuzz

/// Runs `body`; viewcells::Error is the expected answer to bad input, anything else escapes
/// and is a finding.
#define VIEWCELLS_FUZZ_BODY(body) \
  try {                           \
    body;                         \
  } catch (const viewcells::Error&) { \
  }                               \
  return 0
