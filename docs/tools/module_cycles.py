#!/usr/bin/env python3
"""Module import cycles inside each crate of the workspace.

For every crate under the repository root, reads `src/**/*.rs` (binaries
and tests excluded), maps each file to its module path (`a/b.rs` and
`a/b/mod.rs` are `a::b`), and records an edge A -> B when A names
`crate::B...` or `super::...` resolving to B (in `use` lines and in paths
in the code). Edges to a module's own descendants or ancestors count
too, except a parent naming its child (declaring it). Prints the strongly
connected components of more than one module: each is at least one
import cycle. Usage: module_cycles.py [ROOT]
"""
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "."
crates = sorted(d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, "src", "lib.rs")))


def modules(src):
    out = {}
    for dirpath, _, files in os.walk(src):
        if os.path.relpath(dirpath, src).split(os.sep)[0] == "bin":
            continue
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dirpath, f), src)[:-3].split(os.sep)
            if rel[-1] == "mod":
                rel = rel[:-1]
            if rel == ["lib"]:
                rel = []
            out["::".join(rel)] = os.path.join(dirpath, f)
    return out


def strip(code):
    code = re.sub(r"//[^\n]*", "", code)
    return re.sub(r"/\*.*?\*/", "", code, flags=re.S)


def resolve(name, mods):
    """Longest module prefix of a `::` path."""
    parts = name.split("::")
    for k in range(len(parts), 0, -1):
        cand = "::".join(parts[:k])
        if cand in mods:
            return cand
    return None


total = 0
for crate in crates:
    mods = modules(os.path.join(root, crate, "src"))
    edges = {m: set() for m in mods}
    for m, path in mods.items():
        code = strip(open(path).read())
        # Expand `use crate::{a, b::c}` groups one level.
        names = []
        for grp in re.finditer(r"crate::\{([^}]*)\}", code):
            names += [n.strip() for n in grp.group(1).split(",") if n.strip()]
        names += re.findall(r"crate::([A-Za-z_][\w:]*)", code)
        parent = m.rsplit("::", 1)[0] if "::" in m else ""
        for grp in re.finditer(r"super::\{([^}]*)\}", code):
            names += [(parent + "::" if parent else "") + n.strip() for n in grp.group(1).split(",") if n.strip()]
        names += [(parent + "::" if parent else "") + n for n in re.findall(r"super::([A-Za-z_][\w:]*)", code)]
        for n in names:
            t = resolve(n.strip(":"), mods)
            if t is None or t == m or t == "":
                continue
            if t.startswith(m + "::") or m == "":
                continue  # a module naming its own child
            edges[m].add(t)
    # Tarjan's strongly connected components.
    index, low, stack, on, sccs, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                sccs.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in mods:
        if v not in index:
            visit(v)
    for c in sccs:
        print(f"{crate}: " + " <-> ".join(c))
    total += len(sccs)
print(f"{total} import cycle group(s)")
sys.exit(1 if total else 0)
