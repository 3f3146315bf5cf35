#!/usr/bin/env bash
# Fetches OpenArena's Quake 3 levels from Debian's archive without installing the game:
# `apt-get download` of openarena-081-maps, openarena-085-data and openarena-088-data, the
# .pk3 (zip) archives unpacked from the .debs, and every maps/*.bsp extracted into the cache
# (default data/maps, which git ignores). Idempotent: what is there is not fetched again.
# The maps the tests use are checked against their SHA-256.
# Usage: scripts/fetch-maps.sh [CACHE_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
cache="${1:-data/maps}"
mkdir -p "$cache/debs" "$cache/bsp"
# Checksums of the maps tests rely on (from the Debian 12 packages).
declare -A sha256=(
  [oa_dm2]="49f413803bae5a4f799e834c82058cd3622339935d1e0d887e0b08c1b938eafb"
)
packages=(openarena-081-maps openarena-085-data openarena-088-data)
for p in "${packages[@]}"; do
  if ! ls "$cache/debs/${p}"_*.deb >/dev/null 2>&1; then
    echo "fetch-maps: downloading $p"
    download() { (cd "$cache/debs" && apt-get download "$p" 2>&1 | grep -v "^W: Download is performed unsandboxed" || true); }
    download
    if ! ls "$cache/debs/${p}"_*.deb >/dev/null 2>&1; then
      # A fresh machine may not know the package yet: refresh the lists once and retry.
      echo "fetch-maps: refreshing the package lists (apt-get update)"
      SUDO=""
      if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
      $SUDO apt-get update -q >/dev/null
      download
    fi
    ls "$cache/debs/${p}"_*.deb >/dev/null 2>&1 || { echo "fetch-maps: could not download $p" >&2; exit 1; }
  fi
done
for deb in "$cache"/debs/*.deb; do
  stamp="$cache/debs/$(basename "$deb").unpacked"
  [ -f "$stamp" ] && continue
  tmp=$(mktemp -d)
  dpkg-deb -x "$deb" "$tmp"
  # Later archives (pak2 over pak1, 0.8.8 over 0.8.5) replace earlier versions of a map.
  find "$tmp" -name '*.pk3' | sort | while read -r pk3; do
    python3 scripts/vctables.py unpack-maps "$pk3" "$cache/bsp"
  done
  rm -rf "$tmp"
  touch "$stamp"
done
for map in "${!sha256[@]}"; do
  f="$cache/bsp/$map.bsp"
  [ -f "$f" ] || { echo "fetch-maps: $map.bsp is missing from the packages" >&2; exit 1; }
  got=$(sha256sum "$f" | cut -d' ' -f1)
  if [ "${sha256[$map]}" != "$got" ]; then
    echo "fetch-maps: $f has SHA-256 $got, expected ${sha256[$map]}" >&2
    exit 1
  fi
done
echo "fetch-maps: $(ls "$cache/bsp" | wc -l) maps in $cache/bsp"
