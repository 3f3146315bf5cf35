#pragma once
// The .pvs container as the runtime reads it (the format itself: viewcells/format/container.h;
// the payload: viewcells/format/pvs_payload.h).
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

/// The payload of the .pvs file at `path`, checked (format/container.h), and its version.
std::string read_container(const std::string& path, uint32_t& version);
/// The payload of a .pvs file's bytes `file`, checked, and its version.
std::string decode_container(const std::string& file, uint32_t& version);

}  // namespace viewcells::runtime_detail
