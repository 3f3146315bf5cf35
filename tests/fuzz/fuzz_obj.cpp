// libFuzzer target: the OBJ reader and the scene built from it.
#include <sstream>

#include "fuzz_support.h"
#include "viewcells/io/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY({
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    viewcells::make_scene(viewcells::read_obj(in, "fuzz.obj"), viewcells::ObjectGrouping::kAuto, "fuzz.obj");
  });
}
