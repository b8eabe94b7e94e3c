#!/usr/bin/env python3
"""Writes, with h5py, a file in SPH-EXA's H5Part layout (group Step#0, one
1-D dataset per field: x, y, z as float64, h, m, u as float32 like a
single-precision dump, vx, vy, vz; attributes time, iteration, box), for
`sphexa run sedov --init FILE`; then, given the run's output folder,
checks that the run read it: the particle count, and the total energy of
the first step against sum(m u) computed here from the file's values.

usage: init_from_h5py.py write FILE N
       init_from_h5py.py check FILE OUTDIR
"""
import json
import sys

import h5py
import numpy as np


def fail(msg):
    print(f"init_from_h5py: FAIL: {msg}")
    sys.exit(1)


def write(path, n):
    d = 1.0 / n
    c = (np.arange(n) + 0.5) * d - 0.5
    x, y, z = (a.ravel() for a in np.meshgrid(c, c, c, indexing="ij"))
    r2 = x * x + y * y + z * z
    m = np.full(x.size, d**3)
    u = 1e-6 + 10.0 * np.exp(-r2 / 0.01)
    h = np.full(x.size, 1.5 * d)
    with h5py.File(path, "w") as f:
        g = f.create_group("Step#0")
        for name, v in [("x", x), ("y", y), ("z", z), ("vx", 0 * x), ("vy", 0 * x), ("vz", 0 * x)]:
            g.create_dataset(name, data=v.astype(np.float64))
        for name, v in [("h", h), ("m", m), ("u", u)]:
            g.create_dataset(name, data=v.astype(np.float32))
        g.attrs["time"] = 0.0
        g.attrs["iteration"] = 0
        g.attrs["box"] = np.array([-0.5, 0.5, -0.5, 0.5, -0.5, 0.5])


def check(path, out):
    with h5py.File(path, "r") as f:
        g = f["Step#0"]
        m = np.asarray(g["m"], dtype=np.float64)
        u = np.asarray(g["u"], dtype=np.float64)
    summary = json.load(open(f"{out}/summary.json"))
    if summary["particles"] != m.size:
        fail(f"{summary['particles']} particles, the file has {m.size}")
    lines = open(f"{out}/conserved.csv").read().splitlines()
    cols = lines[0].split(",")
    first = dict(zip(cols, map(float, lines[1].split(","))))
    e0 = float(np.sum(m * u))
    if abs(first["E_tot"] / e0 - 1.0) > 1e-6:
        fail(f"E_tot {first['E_tot']} after step 1, sum(m u) of the file {e0}")
    print(f"init_from_h5py: ok ({m.size} particles, E_tot {first['E_tot']:.9e} vs {e0:.9e})")


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "write":
        write(sys.argv[2], int(sys.argv[3]))
    elif len(sys.argv) == 4 and sys.argv[1] == "check":
        check(sys.argv[2], sys.argv[3])
    else:
        fail(__doc__)
