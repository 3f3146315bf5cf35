#!/usr/bin/env python3
"""Where the holes AGVS leaves are, priced: a map's baked PVSs extended without any visibility
test, by the PVSs of each cell's neighbouring cells, or by every object whose bounding box lies
within D units of an object already in the PVS (objects larger than a limit excluded, or not),
each measured by the same play cameras as the bake itself (`viewcells measure MAP PVS --count
300 --seed 7`, 1024x768) and priced in render cost against q3map2's. What these blind filters
close, and at what cost, is what near-object samples (`bake --near-samples`) aim at with rays
instead (docs/accuracy-vs-time.md, section 8).

Usage (the Python module built, its directory on PYTHONPATH):
  scripts/hole-filters.py MAP BASE_PVS OUT_DIR [VIEWCELLS]
Prints a Markdown table.
"""
import json
import os
import subprocess
import sys

import numpy as np

import viewcells

mapname, base, out = sys.argv[1], sys.argv[2], sys.argv[3]
cli = sys.argv[4] if len(sys.argv) > 4 else "build/cli/viewcells"
os.makedirs(out, exist_ok=True)
bsp = f"data/maps/bsp/{mapname}.bsp"
scene = viewcells.Scene.load(bsp)
baked = viewcells.read(base)
lists = [set(baked.pvs(c).tolist()) for c in range(baked.cell_count)]

# Object boxes and the gap between every two (0 where they touch or overlap).
v = scene.vertices[scene.triangles]
o = scene.triangle_objects
n = scene.object_count
lo = np.full((n, 3), np.inf)
hi = np.full((n, 3), -np.inf)
np.minimum.at(lo, o, v.min(axis=1))
np.maximum.at(hi, o, v.max(axis=1))
gap = np.maximum(np.maximum(lo[None, :, :] - hi[:, None, :], lo[:, None, :] - hi[None, :, :]), 0).max(axis=2)
diag = np.linalg.norm(hi - lo, axis=1)

variants = {"AGVS alone (the bake)": base}
neighbours = baked.neighbours
ring = [sorted(lists[c].union(*[lists[k] for k in neighbours[c]])) for c in range(baked.cell_count)]
variants["united with the neighbouring cells' PVSs"] = f"{out}/ring.pvs"
baked.with_pvs(variants["united with the neighbouring cells' PVSs"], ring)
for d, limit in [(4, 512), (32, 512), (4, None)]:
    near = gap <= d
    if limit is not None:
        near &= (diag[:, None] <= limit) & (diag[None, :] <= limit)
    extended = []
    for l in lists:
        ids = np.fromiter(l, dtype=np.int64)
        m = near[ids].any(axis=0)
        m[ids] = True
        extended.append(np.nonzero(m)[0].tolist())
    name = f"every object within {d} units of one in the PVS" + (f" (boxes at most {limit} across)" if limit else "")
    variants[name] = f"{out}/near-{d}-{limit}.pvs"
    baked.with_pvs(variants[name], extended)


def measure(pvs, report):
    args = [cli, "-q", "measure", bsp] + ([pvs] if pvs else []) + ["--count", "300", "--seed", "7", "--report", report]
    subprocess.run(args, check=True)
    return json.load(open(report))


q3 = measure(None, f"{out}/q3map2-m.json")["frame"]["cost"]
print(f"{mapname}: the bake `{base}` and blind extensions of its PVSs, measured by `viewcells measure {bsp} PVS "
      "--count 300 --seed 7` (play cameras, 1024x768). Cost: r(PVS) per frame over q3map2's.\n")
print("| PVSs | mean PVS | cost | frames with a hole | mean wrong pixels | worst |")
print("| --- | ---: | ---: | ---: | ---: | ---: |")
for name, pvs in variants.items():
    m = measure(pvs, pvs[:-4] + "-m.json")
    e = m["pixel_error"]
    size = np.mean([len(viewcells.read(pvs).pvs(c)) for c in range(baked.cell_count)])
    print(f"| {name} | {size:.0f} | {m['frame']['cost'] / q3:.3f} | {100 * e['frames_with_wrong_pixels_share']:.1f}% | "
          f"{e['pixels']:.2f} | {e['worst_pixels']:.0f} |")
