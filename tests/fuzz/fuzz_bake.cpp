// libFuzzer target: see entries.h.
#include "entries.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  viewcells::fuzz::entry_bake(data, size);
  return 0;
}
