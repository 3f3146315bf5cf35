#pragma once
/// An enum's names, written once: to_string and parsing from the same table, and an error that
/// lists every name (so that a new value cannot be left out of one of them).
#include <array>
#include <cstddef>
#include <string>
#include <utility>

#include "viewcells/core/error.h"

namespace viewcells {

template <class E, size_t N>
struct EnumNames {
  std::array<std::pair<E, const char*>, N> names;
  /// What `what` is called in errors ("object grouping").
  const char* what;

  const char* name(E e) const {
    for (const auto& [value, text] : names)
      if (value == e) return text;
    return "?";
  }
  E parse(const std::string& text) const {
    for (const auto& [value, name] : names)
      if (text == name) return value;
    std::string expected;
    for (size_t i = 0; i < N; ++i)
      expected += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + names[i].second;
    throw Error("unknown " + std::string(what) + " '" + text + "' (expected " + expected + ")");
  }
};

}  // namespace viewcells
