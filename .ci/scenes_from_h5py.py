#!/usr/bin/env python3
"""Two scenes of a user's own, written with h5py in SPH-EXA's layout and run
by `sphexa run --init FILE` with no case (the README's worked example):

- blast.h5: a hot spot of energy 1 in a periodic unit cube of density 1
  (attributes box, boundaryType = 1, gamma = 5/3). Checked against the
  Sedov-Taylor radius R = xi (E t^2 / rho)^(1/5), xi = 1.152 for gamma
  5/3 (computed here): the mass-weighted mean radius of the particles
  denser than 1.25 (the shell; 1 ahead of it) within 20% of R at the end time.
- sphere.h5: a cold gas sphere of mass 1 and radius 1 with rho ~ 1/r
  (Evrard's) in an open box (boundaryType = 0, gamma = 5/3, gravConstant
  = 1). Checked: E_grav(0) within 5% of the sphere's -2/3 G M^2 / R (the
  file's G and particles read), it collapses (E_grav at the end below its start by over
  25%, the free fall of ~1.1 time units being well on) while E_tot stays
  within 2% of |E_grav(0)|.

usage: scenes_from_h5py.py SPHEXA_BIN WORKDIR
"""
import csv
import glob
import os
import subprocess
import sys

import h5py
import numpy as np


def fail(msg):
    print(f"scenes_from_h5py: FAIL: {msg}")
    sys.exit(1)


def lattice(n, lo, hi):
    c = lo + (np.arange(n) + 0.5) * (hi - lo) / n
    return [a.ravel() for a in np.meshgrid(c, c, c, indexing="ij")]


def write(path, fields, attrs):
    with h5py.File(path, "w") as f:
        g = f.create_group("Step#0")
        for k, v in attrs.items():
            g.attrs[k] = v
        for k, v in fields.items():
            g[k] = v


def run(sphexa, *args):
    r = subprocess.run([sphexa, "run", *args], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"sphexa run {' '.join(args)}: {r.stderr}")
    return r.stdout


def rows(path):
    with open(path) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def blast(sphexa, work):
    n, t_end, width = 24, 0.02, 0.05
    x, y, z = lattice(n, -0.5, 0.5)
    m = np.full(x.size, 1.0 / x.size)
    r2 = x * x + y * y + z * z
    u = 1e-6 + np.exp(-r2 / width**2) / (np.pi**1.5 * width**3)  # sum m u = 1
    path = os.path.join(work, "blast.h5")
    write(path, dict(x=x, y=y, z=z, m=m, h=np.full(x.size, 1.5 / n), u=u),
          {"box": [-0.5, 0.5, -0.5, 0.5, -0.5, 0.5],
           "boundaryType": np.array([1, 1, 1], dtype=np.int8), "gamma": 5.0 / 3.0})
    out = os.path.join(work, "blast")
    run(sphexa, "--init", path, "--end-time", str(t_end), "--snapshot-at", str(t_end),
        "-q", "--out", out)
    snap = sorted(glob.glob(os.path.join(out, "snapshots", "*.h5")))[-1]
    with h5py.File(snap, "r") as f:
        g = f["Step#0"]
        t = float(np.ravel(g.attrs["time"])[0])
        xs, ys, zs, rho, mm = (g[k][()] for k in ("x", "y", "z", "rho", "m"))
    if abs(t - t_end) > 1e-12:
        fail(f"blast snapshot at t = {t}, not {t_end}")
    shell = rho > 1.25
    if shell.sum() < 10:
        fail(f"blast: {shell.sum()} particles denser than 1.25: no shell")
    r = np.sqrt(xs**2 + ys**2 + zs**2)
    r_shell = float(np.sum(mm[shell] * r[shell]) / np.sum(mm[shell]))
    r_sedov = 1.152 * (1.0 * t_end**2 / 1.0) ** 0.2
    print(f"blast: {x.size} particles to t = {t}: shell radius {r_shell:.4f}, "
          f"Sedov-Taylor {r_sedov:.4f} ({r_shell / r_sedov - 1:+.1%}), peak rho {rho.max():.2f}")
    if abs(r_shell / r_sedov - 1) > 0.2:
        fail("blast: the shell is not within 20% of the Sedov-Taylor radius")


def sphere(sphexa, work):
    n = 20
    x, y, z = lattice(n, -1.0, 1.0)
    r = np.sqrt(x * x + y * y + z * z)
    inside = r < 1.0
    x, y, z, r = x[inside], y[inside], z[inside], r[inside]
    s = np.sqrt(r)  # r -> r^(3/2) turns a uniform ball into rho ~ 1/r
    x, y, z = x * s, y * s, z * s
    m = np.full(x.size, 1.0 / x.size)
    rho = 1.0 / (2.0 * np.pi * np.maximum(r ** 1.5, 1e-3))
    h = 1.3 * (m / rho) ** (1.0 / 3.0)
    path = os.path.join(work, "sphere.h5")
    write(path, dict(x=x, y=y, z=z, m=m, h=h, u=np.full(x.size, 0.05)),
          {"boundaryType": np.array([0, 0, 0], dtype=np.int8), "gamma": 5.0 / 3.0,
           "gravConstant": 1.0})
    out = os.path.join(work, "sphere")
    run(sphexa, "--init", path, "--end-time", "0.6", "-q", "--out", out)
    c = rows(os.path.join(out, "conserved.csv"))
    g0, g1 = c[0]["E_grav"], c[-1]["E_grav"]
    drift = abs(c[-1]["E_tot"] - c[0]["E_tot"]) / abs(g0)
    print(f"sphere: {x.size} particles to t = {c[-1]['t']:.3f}: E_grav {g0:.4f} -> {g1:.4f}, "
          f"E_tot drift {drift:.2e} of |E_grav(0)|")
    if abs(g0 / (-2.0 / 3.0) - 1) > 0.05:
        fail(f"sphere: E_grav(0) = {g0}, not within 5% of -2/3")
    if not g1 < 1.25 * g0:
        fail("sphere: no collapse (E_grav did not fall by 25%)")
    if drift > 0.02:
        fail("sphere: total energy drifted by more than 2%")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        fail(__doc__)
    sphexa, work = sys.argv[1], sys.argv[2]
    os.makedirs(work, exist_ok=True)
    blast(sphexa, work)
    sphere(sphexa, work)
    print("scenes_from_h5py: OK")
