// The .pvs container (container.h), read through the format's (viewcells/format/container.h).
#include "container.h"

#include <fstream>
#include <iterator>
#include <sys/stat.h>

#include "viewcells/format/container.h"

namespace viewcells::runtime_detail {

std::string read_container(const std::string& path, uint32_t& version) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) throw FileError("no such file");
  if (!S_ISREG(st.st_mode)) throw FileError("not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open file");
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return decode_container(file, version);
}

std::string decode_container(const std::string& file, uint32_t& version) {
  try {
    const format::ContainerHeader h = format::read_container_header(file, "VPVS", ".pvs");
    version = h.version();
    if (version != 1 && version != 2)
      throw FileError("format version " + std::to_string(version) + " is not supported (this reader reads 1 and 2)");
    return format::decode_container_payload(file, h);
  } catch (const format::FormatError& e) {
    throw FileError(e.what());
  }
}

}  // namespace viewcells::runtime_detail
