#!/usr/bin/env bash
# Installs dependencies, builds, fetches the OpenArena maps, and runs the whole test suite
# (unit, oracle, invariant, real-map and command-line tests) through ctest. This is the
# command CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# With MPI, so that the suite also runs sampling and AGVS on several ranks (tests/mpi/).
# With the Python module, built for the system Python 3 (pytest runs it: tests/python/).
bash scripts/build.sh build RelWithDebInfo -DVIEWCELLS_BUILD_TESTS=ON -DVIEWCELLS_MPI=ON -DVIEWCELLS_PYTHON=ON \
  -DPython3_EXECUTABLE=/usr/bin/python3 -DPYBIND11_FINDPYTHON=ON
# Real Quake 3 levels from Debian's archive (oa_dm2 is tested); the tests fail without them.
bash scripts/fetch-maps.sh
export VIEWCELLS_REQUIRE_MAPS=1
cd build
# Twice: with the Embree ISA this CPU chooses, and with SSE4.2, whose kernels round the last
# bits of hits differently (no test may depend on one machine's exact samples). A CPU that
# has AVX2 also runs it with AVX2 when that is not already its choice.
ctest --output-on-failure -j "$(nproc)" --timeout 600
supported=$(cli/viewcells isa --supported)
chosen=$(cli/viewcells isa)
for isa in sse4.2 avx2; do
  if grep -qx "$isa" <<<"$supported" && [ "$chosen" != "$isa" ]; then
    echo "test.sh: the suite again with VIEWCELLS_EMBREE_ISA=$isa"
    VIEWCELLS_EMBREE_ISA=$isa ctest --output-on-failure -j "$(nproc)" --timeout 600
  fi
done
