// libFuzzer target: .vagvs solver states (payload inside a valid container) loaded into an
// AGVS solver over a small office, which then samples on: a state that loads must also run
// (candidate origins at 1e300 once reached Embree and aborted). The identity a state must
// carry is kIdentity (scripts/fuzz.sh makes its seeds with it).
#include <cstdlib>

#include "fuzz_support.h"
#include "support/test_scenes.h"
#include "viewcells/agvs/agvs.h"
#include "viewcells/bsp/subdivision.h"
#include "viewcells/raycast/ray_caster.h"
#include "viewcells/scene/generators.h"

namespace {

using namespace viewcells;
constexpr uint64_t kIdentity = 0x5eed;

struct Fixture {
  Scene scene = generate_scene({GeneratorKind::kOffice, 1, 1});
  std::unique_ptr<RayCaster> caster = make_embree_caster(scene);
  CellLocator cells = make_cells();
  AgvsConfig config = make_config();

  CellLocator make_cells() const {
    SubdivisionConfig sc;
    sc.strategy = SplitStrategy::kKdCycling;
    sc.max_cells = 8;
    sc.show_progress = false;
    Subdivision s = subdivide(scene, test::sample_scene(scene, 2000, 3), CostModel{}, sc);
    std::vector<int32_t> leaf_cell(s.nodes.size(), -1);
    const std::vector<int32_t> leaves = s.leaves();
    for (size_t i = 0; i < leaves.size(); ++i) leaf_cell[leaves[i]] = static_cast<int32_t>(i);
    return CellLocator(std::move(s), std::move(leaf_cell), static_cast<uint32_t>(leaves.size()));
  }
  static AgvsConfig make_config() {
    AgvsConfig c;
    c.max_samples = 400;
    c.batch_size = 200;
    c.show_progress = false;
    return c;
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // VIEWCELLS_FUZZ_SEED=PATH: write a state of this fixture (for the seed corpus) and stop.
  if (const char* seed = std::getenv("VIEWCELLS_FUZZ_SEED")) {
    {
      AgvsSolver solver(fixture().scene, *fixture().caster, fixture().cells, fixture().config);
      solver.run();
      solver.save(seed, kIdentity);
    }  // destroyed before exit, so that LeakSanitizer sees it freed
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Fixture& f = fixture();
  const std::string path = fuzz::container_file(data, size, "VAGS", 3, ".vagvs");
  VIEWCELLS_FUZZ_BODY({
    AgvsSolver solver(f.scene, *f.caster, f.cells, f.config);
    solver.load(path, kIdentity);
    solver.set_limits(solver.stats().samples + 400, 0, 0);
    solver.run();
  });
}
