#pragma once
// Formats registered by file extension (the scene readers, the level adapters): one map under a
// lock, filled by front ends at start-up and asked by the library. Lookups return a copy, so a
// format registered again while another thread reads the old one leaves no dangling reference.
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "viewcells/core/error.h"

namespace viewcells {

/// `Format` has `extension` (".bsp", with its dot, lower case) and a callable `read`.
template <class Format>
class ExtensionRegistry {
 public:
  /// Adds `format` (again: replaces the one of the same extension); `who` names the caller in the
  /// error for a format without extension or reader.
  void add(Format format, const char* who) {
    if (format.extension.empty() || format.extension[0] != '.' || !format.read)
      throw Error(std::string(who) + ": an extension with its dot and a reader are needed");
    const std::lock_guard<std::mutex> lock(mutex_);
    std::string ext = format.extension;
    formats_[std::move(ext)] = std::move(format);
  }
  /// The format of `extension` (lower case, with its dot), or none.
  std::optional<Format> find(const std::string& extension) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto it = formats_.find(extension);
    if (it == formats_.end()) return std::nullopt;
    return it->second;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, Format> formats_;
};

}  // namespace viewcells
