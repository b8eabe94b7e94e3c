#!/usr/bin/python3
"""Writes swift_ics_64.hdf5: a SWIFT initial-conditions file as SWIFT's own
example scripts write them with h5py (IC dataset names, GADGET-style scalar
header attributes, f32 positions, masses in MassTable, u32 ids), read by
sph-io's tests/swift.rs, which recomputes every value from the formulas
below.

    /usr/bin/python3 sph-io/tests/data/make_swift_ics.py

Particle i (0..63) sits on a 4^3 lattice, i = 16*ix + 4*iy + iz:
    Coordinates   ((ix, iy, iz) + 0.5) / 4                 f32 (exact)
    Velocities    ((i % 7) - 3) / 8, (i % 5 - 2) / 4, -i/64  f32 (exact)
    SmoothingLength 0.3                                    f32 (rounded)
    InternalEnergy  1.5 + i / 64                           f64
    ParticleIDs     1000 + i                               u32
    mass            MassTable[0] = 1/64 (no Masses dataset)
Header: BoxSize 1.0 (scalar), Time 0.25, Flag_Entropy_ICs 0,
NumFilesPerSnapshot 1, Dimension 3. Units: SWIFT's cosmological example
units (Mpc, 1e10 Msun, Mpc / (km/s)), K, A.
"""

import os

import h5py
import numpy as np

N_SIDE = 4
N = N_SIDE**3
HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "swift_ics_64.hdf5")

i = np.arange(N)
ix, iy, iz = i // 16, (i // 4) % 4, i % 4
pos = ((np.stack([ix, iy, iz], axis=1) + 0.5) / N_SIDE).astype(np.float32)
vel = np.stack([((i % 7) - 3) / 8.0, ((i % 5) - 2) / 4.0, -i / 64.0], axis=1).astype(np.float32)
h = np.full(N, 0.3, dtype=np.float32)
u = 1.5 + i / 64.0
ids = (1000 + i).astype(np.uint32)

with h5py.File(OUT, "w") as f:
    hd = f.create_group("Header")
    hd.attrs["BoxSize"] = 1.0
    hd.attrs["NumPart_ThisFile"] = np.array([N, 0, 0, 0, 0, 0], dtype=np.uint32)
    hd.attrs["NumPart_Total"] = [N, 0, 0, 0, 0, 0]
    hd.attrs["NumPart_Total_HighWord"] = [0, 0, 0, 0, 0, 0]
    hd.attrs["MassTable"] = [1.0 / N, 0.0, 0.0, 0.0, 0.0, 0.0]
    hd.attrs["Time"] = 0.25
    hd.attrs["Flag_Entropy_ICs"] = 0
    hd.attrs["NumFilesPerSnapshot"] = 1
    hd.attrs["Dimension"] = 3
    un = f.create_group("Units")
    un.attrs["Unit length in cgs (U_L)"] = 3.08567758e24
    un.attrs["Unit mass in cgs (U_M)"] = 1.98848e43
    un.attrs["Unit time in cgs (U_t)"] = 3.08567758e19
    un.attrs["Unit current in cgs (U_I)"] = 1.0
    un.attrs["Unit temperature in cgs (U_T)"] = 1.0
    g = f.create_group("PartType0")
    g.create_dataset("Coordinates", data=pos)
    g.create_dataset("Velocities", data=vel)
    g.create_dataset("SmoothingLength", data=h)
    g.create_dataset("InternalEnergy", data=u)
    g.create_dataset("ParticleIDs", data=ids)

print(f"wrote {OUT}: {N} particles")
