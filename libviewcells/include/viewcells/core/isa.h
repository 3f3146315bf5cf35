#pragma once
/// Which of Embree's instruction sets ray casting uses. Embree's kernels (SSE2 to AVX-512)
/// differ in the last bits of their hits, so sampled results are bit-identical across
/// machines only for the same ISA; every report and file header records it. No Embree here:
/// names and CPU features only, so that any module can record the setting.
#include <cstdint>
#include <string>
#include <vector>

namespace viewcells {

/// The Embree ISA casters use by default: the environment variable VIEWCELLS_EMBREE_ISA when
/// set and not empty, else the best this CPU has. Throws Error for a name Embree does not know
/// or an ISA this CPU lacks. Recorded in every report and file header.
std::string embree_isa();
/// Checks an ISA name ("sse2", "sse4.2", "avx", "avx2", "avx512") against this CPU; returns
/// it, or throws Error saying which names are allowed and which this CPU runs.
std::string checked_embree_isa(const std::string& name);
/// The ISAs this CPU can run, best last.
std::vector<std::string> supported_embree_isas();
/// A one-byte code of an ISA name for file headers (0: not recorded) and back.
uint8_t embree_isa_code(const std::string& name);
std::string embree_isa_name(uint8_t code);

}  // namespace viewcells
