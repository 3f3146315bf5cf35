// libFuzzer target: .vcells files (subdivision and merge history, payload inside a valid
// container), and the leaves' adjacency computed from what was read.
#include "fuzz_support.h"
#include "viewcells/bsp/subdivision_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY(viewcells::read_subdivision(viewcells::fuzz::container_file(data, size, "VCEL", 3, ".vcells")));
}
