#pragma once
// The container every file of the toolkit is written in (.pvs, .vcells, .vseg, AGVS states),
// shared by the toolkit (core/binary_file.cpp) and the engines' reader (runtime/): 32 bytes of
// header, then one zstd frame of the payload.
//   bytes 0-3    magic ("VPVS" for a .pvs file)
//   bytes 4-7    version: the low 16 bits the format's version, the third byte the Embree ISA
//                of the process that wrote it (core/isa.h), the fourth byte zero
//   bytes 8-15   payload size
//   bytes 16-23  FNV-1a (64-bit) of the payload
//   bytes 24-31  compressed size: the rest of the file
// Little-endian throughout. Dependencies: zstd alone.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace viewcells::format {

/// A container that cannot be written or read; the message says why, without the path.
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// FNV-1a, 64 bits: the payload's checksum.
uint64_t fnv1a64(const std::string& bytes);

constexpr size_t kContainerHeaderBytes = 32;

/// What the header says.
struct ContainerHeader {
  uint32_t tagged_version = 0;  // as stored: version and ISA
  uint64_t payload_size = 0;
  uint64_t checksum = 0;
  uint64_t compressed_size = 0;
  uint32_t version() const { return tagged_version & 0xffff; }
  uint8_t isa_code() const { return static_cast<uint8_t>(tagged_version >> 16); }
};

/// The whole file: the header for `magic` (4 characters) and `tagged_version`, and the payload
/// compressed by zstd at level 1.
std::string encode_container(const char* magic, uint32_t tagged_version, const std::string& payload);

/// The header of `file`, checked: long enough, the magic, a version field whose fourth byte is
/// zero. `kind` names the file kind in the messages ("not a KIND file (too short)").
ContainerHeader read_container_header(const std::string& file, const char* magic, const std::string& kind);

/// The payload of `file` with header `h` (read_container_header), checked: the compressed size
/// is the rest of the file, the frame says the payload size, at most the size zstd can expand
/// to (a larger claim is refused before anything is allocated), and the checksum.
std::string decode_container_payload(const std::string& file, const ContainerHeader& h);

}  // namespace viewcells::format
