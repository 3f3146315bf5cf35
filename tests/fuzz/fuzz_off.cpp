// libFuzzer target: the OFF reader and the scene built from it.
#include "fuzz_support.h"
#include "viewcells/io/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY({
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    viewcells::make_scene(viewcells::read_off(bytes, "fuzz.off"), viewcells::ObjectGrouping::kAuto, "fuzz.off");
  });
}
