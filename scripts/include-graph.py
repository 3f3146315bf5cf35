#!/usr/bin/env python3
"""The include graph of the project's modules as a Mermaid flowchart, at a git revision.

A module is a directory of libviewcells (include/viewcells/M/ and src/M/), or format, runtime,
studies, cli, capi and python. An arrow A --> B with a count says that many #include lines of A's files name a header
of B. Arrows that run up the layers (the order of libviewcells/CMakeLists.txt's vc_layer calls
at the working tree; format at the bottom, then the library, the runtime beside it, the CLI on
top) or into another module's private sources are drawn red: with one-way layers there are none.

Usage: scripts/include-graph.py [REVISION]   (default: the working tree)
Prints the Markdown block (```mermaid ... ```) and a line counting the red arrows.
"""
import collections
import os
import re
import subprocess
import sys

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
rev = sys.argv[1] if len(sys.argv) > 1 else None


def git(*args):
    return subprocess.run(["git", "-C", here, *args], capture_output=True, text=True, check=True).stdout


def files():
    roots = ["libviewcells", "runtime", "format", "studies", "cli", "capi", "python"]
    if rev:
        names = git("ls-tree", "-r", "--name-only", rev, "--", *roots).split()
    else:
        names = [os.path.relpath(os.path.join(d, f), here) for r in roots
                 for d, _, fs in os.walk(os.path.join(here, r)) for f in fs]
    return [n for n in names if n.endswith((".h", ".hpp", ".cpp"))]


def text(name):
    if rev:
        return git("show", f"{rev}:{name}")
    return open(os.path.join(here, name), errors="replace").read()


def module_of_file(name):
    parts = name.split("/")
    if parts[0] == "libviewcells" and len(parts) > 3 and parts[1] == "include":
        return parts[3]
    if parts[0] == "libviewcells" and len(parts) > 2 and parts[1] == "src":
        return parts[2]
    return parts[0] if parts[0] in ("runtime", "format", "studies", "cli", "capi", "python") else None


def module_of_include(path):
    """(module, private) of an include's quoted path."""
    parts = path.split("/")
    if parts[0] == "viewcells" and len(parts) > 2:
        return parts[1], False
    if path == "viewcells/bake.h":
        return "capi", False  # vc_bake's public header
    if parts[0] == "viewcells":
        return "runtime", False  # viewcells/runtime.hpp, the runtime's public header
    if "runtime" in parts and "src" in parts:
        return "runtime", True
    return None, False


cmake = open(os.path.join(here, "libviewcells", "CMakeLists.txt")).read()
rank = {"format": 0}
for i, m in enumerate(re.finditer(r"vc_layer\((\w+)(.*?)\)", cmake, re.S), 1):
    body = m.group(2).split()
    for src in body[:body.index("BELOW") if "BELOW" in body else len(body)]:
        parts = src.split("/")
        if parts[0] == "src" and len(parts) > 2:
            rank.setdefault(parts[1], i)
top = max(rank.values())
rank.setdefault("cluster", rank.get("core", 1))  # core/cluster before it was core/ranks
rank["runtime"] = 1
rank["studies"] = top + 1  # studies/: above the pipeline, beside the product
rank["cli"] = top + 2
rank["capi"] = rank["python"] = top + 2  # the other front ends, beside the command line

edges = collections.Counter()
red = set()
include = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
names = files()
for name in names:
    a = module_of_file(name)
    if a is None:
        continue
    for path in include.findall(text(name)):
        b, private = module_of_include(path)
        if b is None and "/" not in path and not os.path.exists(os.path.join(here, os.path.dirname(name), path)):
            # A bare name found through an include directory: whose file is it?
            owners = {module_of_file(n) for n in names if n.endswith("/" + path)} - {a}
            if owners:
                b, private = sorted(owners)[0], True
        if b is None or b == a:
            if not private:
                continue
            b = b or "runtime"
        edges[(a, b)] += 1
        if private or rank.get(b, 0) > rank.get(a, top + 1) or (a == "runtime" and b not in ("format", "runtime")):
            red.add((a, b))

print("```mermaid")
print("flowchart BT")
styles = []
for k, ((a, b), n) in enumerate(sorted(edges.items(), key=lambda e: (rank.get(e[0][0], 0), e[0]))):
    print(f"  {a} -->|{n}| {b}")
    if (a, b) in red:
        styles.append(k)
for k in styles:
    print(f"  linkStyle {k} stroke:#d00,stroke-width:3px")
print("```")
print(f"\n{len(red)} red arrows (up the layers or into private sources): "
      + (", ".join(f"{a} -> {b}" for a, b in sorted(red)) or "none") + ".")
