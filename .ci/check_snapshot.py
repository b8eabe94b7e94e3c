#!/usr/bin/env python3
"""Opens a snapshot written by `sphexa run` with h5py (the HDF5 C library)
and checks it independently of the Rust reader: the H5Part layout (group
Step#0, one 1-D dataset per field), field names and lengths, the step
attributes, every field's CRC32 (recomputed here with zlib), and values of
a few particles of a Sedov run.

usage: check_snapshot.py SNAPSHOT.h5 N FIELD[,FIELD...]
"""
import sys
import zlib

import h5py
import numpy as np


def fail(msg):
    print(f"check_snapshot: FAIL: {msg}")
    sys.exit(1)


def main():
    if len(sys.argv) != 4:
        fail(__doc__)
    path, n, fields = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(",")
    with h5py.File(path, "r") as f:
        if list(f.keys()) != ["Step#0"]:
            fail(f"groups {list(f.keys())}, expected ['Step#0']")
        g = f["Step#0"]
        if sorted(g.keys()) != sorted(fields):
            fail(f"datasets {sorted(g.keys())}, expected {sorted(fields)}")
        a = g.attrs
        for key in ["time", "iteration", "minDt", "box", "periodic", "numParticles", "case", "config"]:
            if key not in a:
                fail(f"attribute '{key}' missing (has {sorted(a.keys())})")
        if int(a["numParticles"]) != n:
            fail(f"numParticles {a['numParticles']}, expected {n}")
        box = np.asarray(a["box"], dtype=np.float64)
        if box.shape != (6,):
            fail(f"box {box}")
        case = a["case"].decode() if isinstance(a["case"], bytes) else str(a["case"])
        if case != "sedov":
            fail(f"case {case!r}")
        if not (float(a["time"]) > 0 and float(a["minDt"]) > 0 and int(a["iteration"]) > 0):
            fail(f"time {a['time']} minDt {a['minDt']} iteration {a['iteration']}")
        listed = [s.decode() if isinstance(s, bytes) else s for s in a["sph_io_fields"]]
        if listed != fields:
            fail(f"sph_io_fields {listed}, expected {fields} (in order)")
        for name in fields:
            d = g[name]
            if d.shape != (n,):
                fail(f"{name}: shape {d.shape}, expected ({n},)")
            values = d[...]
            want = np.uint64 if name == "id" else np.float64
            if values.dtype != want:
                fail(f"{name}: dtype {values.dtype}, expected {want}")
            crc = zlib.crc32(values.astype(values.dtype.newbyteorder("<")).tobytes())
            if crc != int(d.attrs["crc32"]):
                fail(f"{name}: crc32 {crc:#010x}, stored {int(d.attrs['crc32']):#010x}")
        # Values of a few particles (Sedov: a lattice of equal masses in the
        # periodic box [-0.5, 0.5]^3, every id once).
        ids = g["id"][...]
        if sorted(ids.tolist()) != list(range(n)):
            fail("ids are not 0..N-1, each once")
        if "m" in g and not np.all(g["m"][...] == 1.0 / n):
            fail("masses are not 1/N")
        for axis, k in (("x", 0), ("y", 2), ("z", 4)):
            if axis in g:
                v = g[axis][...]
                if not (np.all(v >= box[k]) and np.all(v <= box[k + 1])):
                    fail(f"{axis} outside the box {box[k]}..{box[k + 1]}")
        if "rho" in g and not np.all(g["rho"][...] > 0):
            fail("a density is not positive")
        order = np.argsort(ids)
        first = {name: g[name][...][order[:3]].tolist() for name in fields if name != "id"}
    print(f"check_snapshot: {path}: {n} particles, fields {','.join(fields)}, checksums match; particles 0-2: {first}")


if __name__ == "__main__":
    main()
