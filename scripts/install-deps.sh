#!/usr/bin/env bash
# Installs every build, test and plotting dependency of viewcells from Debian 12 packages.
# Idempotent: packages already present are skipped, and apt is only asked when something is missing.
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
  libgtest-dev libgmock-dev libbenchmark-dev   # tests and micro-benchmarks
  gnuplot-nox                                  # plots of comparisons and studies (scripts/plot-*.sh)
)

# scripts/fuzz.sh also needs clang with libFuzzer's runtime.
if [ "${1:-}" = "--fuzz" ]; then packages+=(clang-14 libclang-rt-14-dev); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
