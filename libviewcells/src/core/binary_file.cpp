/// The toolkit's versioned, checksummed, zstd-compressed binary container.
#include "viewcells/core/binary_file.h"

#include "viewcells/core/ranks.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>

#include "viewcells/core/isa.h"
#include "viewcells/format/container.h"

namespace viewcells {

uint64_t fnv1a64(const std::string& bytes) { return format::fnv1a64(bytes); }

namespace {

/// The open OutputBatch's staged files (tmp, target), or null when none is open: per thread,
/// so that a file written on one thread (Python's write_gltf) is not held back by a bake
/// running on another, and two bakes in one process each keep their own batch.
std::mutex g_batch_mutex;
thread_local std::vector<std::pair<std::string, std::string>>* g_batch = nullptr;
std::atomic<uint64_t> g_temporaries{0};

}  // namespace

void check_output_target(const std::string& path) {
  if (path.empty()) throw Error("an output file needs a name (an empty path was given)");
  std::error_code ec;
  const auto st = std::filesystem::symlink_status(path, ec);
  if (!ec && st.type() != std::filesystem::file_type::not_found && st.type() != std::filesystem::file_type::regular)
    throw Error(path, 0, "exists and is not a regular file (a directory, device, FIFO or symbolic link): outputs are "
                         "replaced by new files, so viewcells will not write there");
  // The new file is made beside it and renamed into place: its directory must be there.
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  const std::filesystem::path dir = parent.empty() ? std::filesystem::path(".") : parent;
  if (!std::filesystem::is_directory(dir, ec))
    throw Error(path, 0, "cannot be written: its directory " + dir.string() + " does not exist");
  if (access(dir.c_str(), W_OK) != 0)
    throw Error(path, 0, "cannot be written: its directory " + dir.string() + " is not writable");
}

std::string temporary_for(const std::string& path) {
  // Unique within the process too: two threads may write files of the same name at once.
  return path + ".tmp." + std::to_string(getpid()) + "." + std::to_string(g_temporaries.fetch_add(1));
}

void install_file(const std::string& tmp, const std::string& path) {
  {
    std::lock_guard lock(g_batch_mutex);
    if (g_batch) {
      for (auto& [staged, target] : *g_batch)
        if (target == path) {
          if (staged != tmp) std::remove(staged.c_str());
          staged = tmp;
          return;
        }
      g_batch->push_back({tmp, path});
      return;
    }
  }
  if (!ranks::writer()) {  // on a cluster, rank 0 writes; the others hold the same result
    std::remove(tmp.c_str());
    return;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw Error(path, 0, "cannot replace file: " + ec.message());
  }
}

std::string staged_path(const std::string& path) {
  std::lock_guard lock(g_batch_mutex);
  if (g_batch)
    for (const auto& [staged, target] : *g_batch)
      if (target == path) return staged;
  return path;
}

UnbatchedWrites::UnbatchedWrites() {
  std::lock_guard lock(g_batch_mutex);
  saved_ = g_batch;
  g_batch = nullptr;
}

UnbatchedWrites::~UnbatchedWrites() {
  std::lock_guard lock(g_batch_mutex);
  g_batch = saved_;
}

OutputBatch::OutputBatch() {
  std::lock_guard lock(g_batch_mutex);
  VC_CHECK(g_batch == nullptr);
  g_batch = &staged_;
}

OutputBatch::~OutputBatch() {
  std::lock_guard lock(g_batch_mutex);
  for (const auto& [staged, target] : staged_) std::remove(staged.c_str());
  g_batch = nullptr;
}

void OutputBatch::commit() {
  std::vector<std::pair<std::string, std::string>> files;
  {
    std::lock_guard lock(g_batch_mutex);
    files.swap(staged_);
    g_batch = nullptr;
  }
  for (size_t i = 0; i < files.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(files[i].first, files[i].second, ec);
    if (ec) {
      for (size_t j = i; j < files.size(); ++j) std::remove(files[j].first.c_str());
      throw Error(files[i].second, 0, "cannot replace file: " + ec.message());
    }
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  check_output_target(path);
  const std::string tmp = temporary_for(path);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path, 0, "cannot open for writing");
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw Error(path, 0, "write failed (disk full?)");
    }
  }
  install_file(tmp, path);
}

std::string read_all(std::istream& in, const std::string& name) {
  std::string bytes;
  char block[1 << 16];
  while (in.read(block, sizeof block) || in.gcount() > 0) bytes.append(block, static_cast<size_t>(in.gcount()));
  if (in.bad()) throw Error(name, 0, "read error");
  return bytes;
}

std::string read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, 0, "cannot open file");
  in.seekg(0, std::ios::end);
  const std::streamoff length = in.tellg();
  in.seekg(0, std::ios::beg);
  if (!in || length < 0) {  // not seekable: block by block
    in.clear();
    return read_all(in, path);
  }
  std::string bytes(static_cast<size_t>(length), '\0');
  in.read(bytes.data(), length);
  if (in.bad()) throw Error(path, 0, "read error");
  bytes.resize(static_cast<size_t>(in.gcount()));  // shorter if it shrank meanwhile,
  bytes += read_all(in, path);                      // and the rest if it grew
  return bytes;
}

std::string container_image(const char (&magic)[5], uint32_t version, const std::string& payload) {
  // The version's third byte records the Embree ISA of the writing process (core/isa.h).
  VC_CHECK(version > 0 && version <= 0xffff);
  try {
    return format::encode_container(magic, version | static_cast<uint32_t>(embree_isa_code(embree_isa())) << 16,
                                    payload);
  } catch (const format::FormatError& e) {
    throw Error(e.what());
  }
}

void write_container(const std::string& path, const char (&magic)[5], uint32_t version,
                     const std::string& payload) {
  std::string file;
  try {
    file = container_image(magic, version, payload);
  } catch (const Error& e) {
    throw Error(path, 0, e.what());
  }
  write_text_file(path, file);
}

std::string read_container(const std::string& path, const char (&magic)[5], uint32_t max_version,
                           uint32_t& version, std::string* isa) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(path, 0, std::filesystem::exists(path, ec) ? "not a regular file" : "no such file");
  // Read in blocks, not through a character iterator (BENCHMARKS.md, "Decisions measured").
  const std::string file = read_file_bytes(path);
  try {
    const format::ContainerHeader h = format::read_container_header(file, magic, magic);
    version = h.version();
    if (isa) *isa = embree_isa_name(h.isa_code());
    if (version == 0 || version > max_version)
      throw Error(path, 0, "format version " + std::to_string(version) + " is not supported (this build reads up to " +
                               std::to_string(max_version) + ")");
    return format::decode_container_payload(file, h);
  } catch (const format::FormatError& e) {
    throw Error(path, 0, e.what());
  }
}

}  // namespace viewcells
