#pragma once
// What each libFuzzer target does with one input, shared with the unit test that replays the
// saved findings (data/fuzz/regressions/FORMAT/). viewcells::Error is the expected answer to
// bad input and is swallowed; anything else (another exception, a crash, a sanitizer report)
// is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

namespace viewcells::fuzz {

void entry_obj(const uint8_t* data, size_t size);
void entry_ply(const uint8_t* data, size_t size);
void entry_off(const uint8_t* data, size_t size);
void entry_stl(const uint8_t* data, size_t size);
void entry_bsp(const uint8_t* data, size_t size);
/// Scene-graph formats through Assimp: binary glTF and FBX.
void entry_glb(const uint8_t* data, size_t size);
void entry_fbx(const uint8_t* data, size_t size);
/// The toolkit's own formats: the input is a payload (its first byte picks the format
/// version), wrapped in a valid container so that it gets past the checksum.
void entry_vseg(const uint8_t* data, size_t size);
void entry_vcells(const uint8_t* data, size_t size);
void entry_pvs(const uint8_t* data, size_t size);
/// The engines' reader (runtime/): bytes 1-48 of the input are two query points (raw doubles),
/// the rest a .pvs payload in a valid container; every C API call, checked against the toolkit.
void entry_runtime(const uint8_t* data, size_t size);
/// vc_bake on objects and option words from the bytes (see entries.cpp), its result opened by
/// the runtime from memory; the same bytes through vc_pvs_open_memory.
void entry_bake(const uint8_t* data, size_t size);
/// Loads the state into an AGVS solver over a small office, and samples on when it loads.
void entry_vagvs(const uint8_t* data, size_t size);
/// Writes a state of entry_vagvs's solver (for the seed corpus).
void write_vagvs_seed(const std::string& path);

}  // namespace viewcells::fuzz
