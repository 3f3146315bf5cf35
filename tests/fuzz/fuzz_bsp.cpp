// libFuzzer target: the Quake 3 BSP reader and the world mesh made from it.
#include "fuzz_support.h"
#include "viewcells/io/q3bsp.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY({
    const viewcells::Q3Map map = viewcells::parse_q3bsp(std::string(reinterpret_cast<const char*>(data), size), "fuzz.bsp");
    viewcells::q3_world_mesh(map);
  });
}
