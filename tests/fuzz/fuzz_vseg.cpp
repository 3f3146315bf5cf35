// libFuzzer target: .vseg segment files (payload inside a valid container).
#include "fuzz_support.h"
#include "viewcells/sampling/segments.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY(viewcells::read_segments(viewcells::fuzz::container_file(data, size, "VSEG", 1, ".vseg")));
}
