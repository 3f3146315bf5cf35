#!/usr/bin/env python3
"""Fails when an include runs up the library's layers.

The layers and what lies below each are read from libviewcells/CMakeLists.txt (the
`vc_layer(NAME src/DIR/FILE.cpp ... BELOW LAYER ...)` calls): a layer owns the directories of
its sources, under src/ and include/viewcells/. A file may include the headers of its own
layer, of the layers below it (transitively) and of the format (viewcells/format/), and nothing
else of the project's: not a layer above or beside it, not the runtime's sources.

Usage: tools/check-layers.py [LIBVIEWCELLS_DIR]   (default: libviewcells beside this script)
Prints FILE:LINE: what runs up, for each such include, and exits 1 if there is any.
"""
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "libviewcells")
cmake = open(os.path.join(root, "CMakeLists.txt")).read()
owner, below = {}, {}
for m in re.finditer(r"vc_layer\((\w+)(.*?)\)", cmake, re.S):
    name, body = m.group(1), m.group(2).split()
    cut = body.index("BELOW") if "BELOW" in body else len(body)
    below[name] = body[cut + 1:]
    for src in body[:cut]:
        parts = src.split("/")
        if parts[0] == "src" and len(parts) > 2:
            if owner.setdefault(parts[1], name) != name:
                sys.exit(f"check-layers: directory {parts[1]} has sources in layers {owner[parts[1]]} and {name}")
if not owner:
    sys.exit(f"check-layers: no vc_layer() calls in {root}/CMakeLists.txt")


def under(layer, seen=None):
    seen = set() if seen is None else seen
    for b in below.get(layer, []):
        if b not in seen:
            seen.add(b)
            under(b, seen)
    return seen


allowed = {layer: {layer} | under(layer) for layer in below}
include = re.compile(r'\s*#\s*include\s+"([^"]+)"')
problems = []
for base in ("src", os.path.join("include", "viewcells")):
    top = os.path.join(root, base)
    for directory, _, files in os.walk(top):
        rel = os.path.relpath(directory, top)
        if rel == ".":
            continue
        module = rel.split(os.sep)[0]
        layer = owner.get(module)
        if layer is None:
            problems.append(f"{directory}: directory {module} belongs to no layer (libviewcells/CMakeLists.txt)")
            continue
        for name in sorted(files):
            path = os.path.join(directory, name)
            with open(path, errors="replace") as f:
                for number, line in enumerate(f, 1):
                    m = include.match(line)
                    if not m:
                        continue
                    target = m.group(1)
                    parts = target.split("/")
                    if parts[0] == "viewcells":
                        parts = parts[1:]
                    if len(parts) < 2:
                        continue  # a file beside it
                    if parts[0] == "format":
                        continue
                    theirs = owner.get(parts[0])
                    if theirs is None:
                        problems.append(f"{path}:{number}: includes {target}, which is in no layer of the library")
                    elif theirs not in allowed[layer]:
                        problems.append(f"{path}:{number}: layer {layer} includes {target} of layer {theirs}, "
                                        f"which is not below it (below {layer}: {', '.join(sorted(under(layer))) or 'nothing'})")
for p in problems:
    print(p)
sys.exit(1 if problems else 0)
