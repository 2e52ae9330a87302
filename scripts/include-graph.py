#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The house map from the code itself (docs/architecture.md).

Reads every `#include "..."` of the tree (not tests/, bench/, examples/, build*/ unless --all),
resolves it to a file of the repository, and prints:
  1. the folder-level graph: which folder includes which, with a count of includes;
  2. arrows that go up a floor (a lower floor including a higher one), by the floors below;
  3. circles of files: a file that reaches itself through includes, or through a header whose
     free functions are defined in several sources of its folder (A.cpp includes X.hpp, whose
     function f is defined in B.cpp, and B.cpp includes X.hpp for a function defined in A.cpp).
A header and the source that defines it (the public headers' pairing with their sources) are one
unit, so include/ -> src/ of one folder is never an arrow.
Exit code 1 when there is an arrow up a floor or a circle of files: the rule the next session checks.
"""
import argparse
import collections
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP_TOP = {"tests", "bench", "examples", "deploy", "cmake", "config", "docs", "scripts"}
EXTS = (".hpp", ".h", ".cpp", ".c", ".cc", ".ipp")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)

# The floors of the house, lowest first. A folder may include its own floor and those below.
FLOORS = [
    ("core", ["include/sim", "sim"]),
    # Header-only, what every family's decoder shares (CompletedFrame, FrameOutput, readers).
    ("LiDAR decoder common", ["drivers/common/decoder"]),
    ("timing and imaging", ["timing", "imaging"]),
    ("drivers/common", ["drivers/common"]),
    ("apps", ["apps"]),  # the programs' shared layer
    ("drivers/common/program", ["drivers/common/program"]),
    ("family decoders", ["drivers/hesai", "drivers/ouster", "drivers/velodyne", "drivers/unitree",
                         "drivers/camera"]),
    ("family streams", ["drivers/hesai/stream", "drivers/ouster/stream", "drivers/velodyne/stream",
                        "drivers/unitree/stream"]),
    ("family programs", ["drivers/hesai/program", "drivers/ouster/program", "drivers/velodyne/program",
                         "drivers/unitree/program",
                         "drivers/hesai/tools", "drivers/ouster/tools", "drivers/velodyne/tools",
                         "drivers/unitree/tools", "drivers/camera/tools"]),
    ("replay", ["replay"]),
    ("top", ["tools", "bridge", "viewer", "mcap", "ros2", "python"]),
]


def component(rel):
    """The folder a file belongs to: its path without include/… or src/…"""
    parts = rel.split("/")
    for i, p in enumerate(parts[:-1]):
        if p in ("include", "src"):
            if i == 0:  # include/sim/… is the core's public side
                return "include/sim"
            return "/".join(parts[:i])
    return "/".join(parts[:-1]) or "."


def floor_of(comp):
    best = None
    for rank, (_, folders) in enumerate(FLOORS):
        for f in folders:
            if comp == f or comp.startswith(f + "/"):
                if best is None or len(f) > best[1]:
                    best = (rank, len(f))
    return None if best is None else best[0]


def collect(all_files):
    files = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        rel_dir = os.path.relpath(dirpath, ROOT)
        top = rel_dir.split("/")[0]
        dirnames[:] = [d for d in dirnames if not d.startswith(".") and not d.startswith("build")]
        if rel_dir != "." and not all_files and top in SKIP_TOP:
            dirnames[:] = []
            continue
        for name in filenames:
            if name.endswith(EXTS):
                files.append(os.path.normpath(os.path.join(rel_dir, name)))
    return sorted(files)


def resolve(includer, target, by_suffix):
    here = os.path.normpath(os.path.join(os.path.dirname(includer), target))
    if here in by_suffix["__all__"]:
        return here
    hits = by_suffix.get(target, [])
    if len(hits) == 1:
        return hits[0]
    if hits:  # the nearest: same top folder first
        top = includer.split("/")[0]
        same = [h for h in hits if h.split("/")[0] == top]
        return (same or hits)[0]
    return None


DECL = re.compile(r"^[A-Za-z_][\w:<>,\s\*&]*?[\s\*&]([a-z_]\w*)\(", re.M)


def definitions(text):
    """Names of functions defined at column 0 in a source (namespaces are not indented here)."""
    names = set()
    # Helpers in an anonymous namespace are no header's definition.
    text = re.sub(r"^namespace \{\n.*?^\}  // namespace\n", "", text, flags=re.M | re.S)
    for m in re.finditer(r"^(?!static\b)[A-Za-z_][^;\n]*?\b([a-z_]\w*)\(([^;{]*?)\)[^;{]*\{", text, re.M | re.S):
        names.add(m.group(1))
    return names


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--all", action="store_true", help="also tests/, bench/, examples/")
    ap.add_argument("--files", action="store_true", help="print the file-level arrows up a floor")
    args = ap.parse_args()

    files = collect(args.all)
    by_suffix = collections.defaultdict(list)
    by_suffix["__all__"] = set(files)
    for f in files:
        parts = f.split("/")
        for i in range(len(parts)):
            by_suffix["/".join(parts[i:])].append(f)

    text = {}
    for f in files:
        with open(os.path.join(ROOT, f), encoding="utf-8", errors="replace") as fh:
            text[f] = fh.read()

    edges = collections.defaultdict(set)       # file -> files it includes
    unresolved = collections.Counter()
    for f in files:
        for inc in INCLUDE.findall(text[f]):
            r = resolve(f, inc, by_suffix)
            if r is None:
                unresolved[inc] += 1
            elif r != f:
                edges[f].add(r)

    # Units: a header and the sources of its folder that define it.
    stem_sources = collections.defaultdict(list)
    for f in files:
        if f.endswith((".cpp", ".c", ".cc")):
            stem_sources[(component(f), os.path.splitext(os.path.basename(f))[0])].append(f)
    defined = {f: definitions(text[f]) for f in files if f.endswith((".cpp", ".c", ".cc"))}
    definers = collections.defaultdict(set)     # header -> sources that define it
    for f in files:
        if not f.endswith((".hpp", ".h")):
            continue
        comp = component(f)
        stem = os.path.splitext(os.path.basename(f))[0]
        paired = stem_sources.get((comp, stem), [])
        definers[f].update(paired)
        if paired:
            continue
        declared = set(DECL.findall(text[f]))
        for src, names in defined.items():
            if component(src) == comp and declared & names:
                definers[f].add(src)

    # 1. folder graph
    folder = collections.Counter()
    for f, targets in edges.items():
        for t in targets:
            a, b = component(f), component(t)
            if a != b:
                folder[(a, b)] += 1
    print("# folder-level include graph (includer -> included: includes)")
    for (a, b), n in sorted(folder.items()):
        print(f"{a} -> {b}: {n}")

    # 2. arrows up a floor
    bad = 0
    print("\n# arrows up a floor (a lower floor includes a higher one)")
    for (a, b), n in sorted(folder.items()):
        fa, fb = floor_of(a), floor_of(b)
        if fa is not None and fb is not None and fb > fa:
            bad += 1
            print(f"UP {a} (floor {FLOORS[fa][0]}) -> {b} (floor {FLOORS[fb][0]}): {n}")
            if args.files:
                for f, targets in sorted(edges.items()):
                    for t in sorted(targets):
                        if component(f) == a and component(t) == b:
                            print(f"    {f} -> {t}")
    unplaced = sorted({c for pair in folder for c in pair if floor_of(c) is None})
    if unplaced:
        print("folders on no floor: " + ", ".join(unplaced))

    # 3. circles of files (Tarjan on includes + header -> defining sources)
    graph = collections.defaultdict(set)
    for f, targets in edges.items():
        for t in targets:
            graph[f].add(t)
            if f.endswith((".hpp", ".h")):
                continue  # a header needs the declarations; its includer's source needs the definers
            for src in definers.get(t, ()):
                if src != f:
                    graph[f].add(src)
    index, low, on, stack, sccs = {}, {}, set(), [], []
    counter = [0]
    sys.setrecursionlimit(100000)

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                sccs.append(sorted(scc))

    for v in list(graph):
        if v not in index:
            strong(v)
    print("\n# circles of files (through includes, or a header defined in several sources)")
    for scc in sorted(sccs):
        bad += 1
        print("CIRCLE " + " <-> ".join(scc))
    if not sccs:
        print("none")
    if unresolved:
        print("\n# includes not found in the tree (generated or system headers): "
              + ", ".join(sorted(unresolved)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
