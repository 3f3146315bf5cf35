/// Which Embree instruction set ray casting uses (recorded in every report and file header).
#include "viewcells/core/isa.h"

#include <cstdlib>
#include <iterator>

#include "viewcells/core/error.h"

namespace viewcells {
namespace {

/// Embree's ISA names, worst first, with the CPU features each needs.
struct IsaInfo {
  const char* name;
  bool (*supported)();
};
const IsaInfo kIsas[] = {
    {"sse2", [] { return static_cast<bool>(__builtin_cpu_supports("sse2")); }},
    {"sse4.2", [] { return static_cast<bool>(__builtin_cpu_supports("sse4.2")); }},
    {"avx", [] { return static_cast<bool>(__builtin_cpu_supports("avx")); }},
    {"avx2", [] { return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2"); }},
    {"avx512", [] {
       return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
              __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512bw") &&
              __builtin_cpu_supports("avx512vl");
     }},
};

}  // namespace

std::vector<std::string> supported_embree_isas() {
  std::vector<std::string> out;
  for (const IsaInfo& i : kIsas)
    if (i.supported()) out.push_back(i.name);
  return out;
}

std::string checked_embree_isa(const std::string& name) {
  std::string known;
  for (const IsaInfo& i : kIsas) {
    known += (known.empty() ? "" : ", ") + std::string(i.name);
    if (name != i.name) continue;
    if (!i.supported()) {
      std::string have;
      for (const std::string& s : supported_embree_isas()) have += (have.empty() ? "" : ", ") + s;
      throw Error("Embree ISA '" + name + "' is not supported by this CPU (it runs " + have + ")");
    }
    return name;
  }
  throw Error("unknown Embree ISA '" + name + "' (expected one of " + known + ")");
}

std::string embree_isa() {
  const char* env = std::getenv("VIEWCELLS_EMBREE_ISA");
  if (env && *env) {
    try {
      return checked_embree_isa(env);
    } catch (const Error& e) {
      throw Error(std::string("VIEWCELLS_EMBREE_ISA: ") + e.what());
    }
  }
  const std::vector<std::string> all = supported_embree_isas();
  if (all.empty()) throw Error("this CPU lacks SSE2, which Embree needs");
  return all.back();
}

uint8_t embree_isa_code(const std::string& name) {
  for (size_t i = 0; i < std::size(kIsas); ++i)
    if (name == kIsas[i].name) return static_cast<uint8_t>(i + 1);
  return 0;
}

std::string embree_isa_name(uint8_t code) {
  return code >= 1 && code <= std::size(kIsas) ? kIsas[code - 1].name : "not recorded";
}

}  // namespace viewcells
