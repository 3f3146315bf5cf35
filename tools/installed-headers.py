#!/usr/bin/env python3
"""The library's headers to install: those of the stable modules (the pipeline, scenes and
their readers) and every header they include, transitively; nothing else. Internals that no
stable header needs (threads, progress, MPI ranks, file staging, ...) stay private.

Usage: tools/installed-headers.py INCLUDE_DIR MODULE...   (e.g. libviewcells/include pipeline scene io)
A MODULE that ends in .h is that header alone (e.g. q3/bsp_file.h: the Quake 3 reader that a
consumer registers, without the rest of the adapter).
Prints the headers, relative to INCLUDE_DIR, separated by semicolons (a CMake list).
"""
import os
import re
import sys

include_dir, modules = sys.argv[1], sys.argv[2:]
found = re.compile(r'\s*#\s*include\s+"(viewcells/[^"]+)"')
todo = []
for module in modules:
    if module.endswith(".h"):
        if not os.path.isfile(os.path.join(include_dir, "viewcells", module)):
            sys.exit(f"installed-headers: no header {module} in {include_dir}/viewcells")
        todo.append(os.path.join("viewcells", module))
        continue
    top = os.path.join(include_dir, "viewcells", module)
    if not os.path.isdir(top):
        sys.exit(f"installed-headers: no module {module} in {include_dir}/viewcells")
    for directory, _, files in os.walk(top):
        todo += [os.path.relpath(os.path.join(directory, f), include_dir) for f in files if f.endswith(".h")]
seen = set()
while todo:
    header = todo.pop()
    if header in seen:
        continue
    seen.add(header)
    with open(os.path.join(include_dir, header)) as f:
        for line in f:
            m = found.match(line)
            if m and os.path.exists(os.path.join(include_dir, m.group(1))):
                todo.append(m.group(1))
print(";".join(sorted(seen)), end="")
