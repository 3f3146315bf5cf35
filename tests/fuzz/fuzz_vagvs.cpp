// libFuzzer target: see entries.h. VIEWCELLS_FUZZ_SEED=PATH writes a state for the seed
// corpus and exits.
#include <cstdlib>

#include "entries.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* seed = std::getenv("VIEWCELLS_FUZZ_SEED")) {
    viewcells::fuzz::write_vagvs_seed(seed);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  viewcells::fuzz::entry_vagvs(data, size);
  return 0;
}
