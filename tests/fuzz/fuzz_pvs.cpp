// libFuzzer target: .pvs files (cells, BSP and compressed PVSs, payload inside a valid
// container), then a point lookup and the PVS of the cell found.
#include "fuzz_support.h"
#include "viewcells/pvs/pvs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  VIEWCELLS_FUZZ_BODY({
    const viewcells::PvsFile f = viewcells::read_pvs(viewcells::fuzz::container_file(data, size, "VPVS", 1, ".pvs"));
    // Point location walks the BSP read from the file: a corrupt tree must not loop or run off.
    const viewcells::Box3& b = f.bsp.view_box;
    f.locate(b.center());
    f.locate(b.lo);
  });
}
