// libFuzzer target: the STL reader and the scene built from it.
#include "fuzz_support.h"
#include "viewcells/io/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY({
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    viewcells::make_scene(viewcells::read_stl(bytes, "fuzz.stl"), viewcells::ObjectGrouping::kAuto, "fuzz.stl");
  });
}
