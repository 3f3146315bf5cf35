#!/usr/bin/env bash
# Installs every build, test and plotting dependency of viewcells from Debian 12 packages, and the
# web viewer's (three.js, esbuild, playwright-core) from the npm registry into web/node_modules,
# pinned by web/package-lock.json.
# Idempotent: packages already present are skipped, and apt and npm are only asked when something
# is missing.
# Usage: scripts/install-deps.sh [--fuzz]
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config python3
  jq                     # the command-line test reads the JSON reports (python3 starts slowly)
  libembree-dev          # ray casting (Embree 3.13)
  libcgal-dev libgmp-dev libmpfr-dev   # exact predicates (header-only CGAL 5.5)
  libboost-graph-dev     # neighbour graph of view cells
  libtbb-dev             # parallelism
  libcli11-dev           # command line
  nlohmann-json3-dev     # reports and configuration
  libzstd-dev            # compressed binary files
  libpng-dev             # slice images
  libassimp-dev          # glTF, FBX and other scene-graph formats
  assimp-testmodels      # real models in those formats, for the tests
  chromium               # the web viewer's test, headless
  libopenmpi-dev openmpi-bin   # several ranks (VIEWCELLS_MPI; the tests build with it)
  libgtest-dev libgmock-dev libbenchmark-dev   # tests and micro-benchmarks
  gnuplot-nox                                  # plots of comparisons and studies (scripts/plot-*.sh)
  valgrind               # instruction counts of an A/B benchmark (scripts/bench.sh ab-instructions)
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest   # the Python module (python/) and its tests
  blender                # the module inside Blender 3.4, headless (tests/blender/)
  xvfb xauth             # Blender with a window, on a virtual X server (tests/blender/addon_gui_test.py),
  libgl1-mesa-dri        # drawing its OpenGL in software (Mesa)
)

# scripts/fuzz.sh also needs clang with libFuzzer's runtime.
if [ "${1:-}" = "--fuzz" ]; then packages+=(clang-14 libclang-rt-14-dev); fi

# Node.js and npm build the web viewer; Debian's serve when the machine has none of its own.
if ! command -v npm >/dev/null 2>&1; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
else
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# The web viewer's packages, exactly as the lockfile pins them (npm ci), unless already there.
web="$(cd "$(dirname "$0")/.." && pwd)/web"
if [ ! -f "$web/node_modules/.package-lock.json" ] || [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  echo "install-deps: npm ci in web/"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
else
  echo "install-deps: web/node_modules up to date"
fi
