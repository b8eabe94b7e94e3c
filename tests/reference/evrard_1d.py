#!/usr/bin/env python3
"""Evrard collapse in 1-D: spherical Lagrangian hydrodynamics with self-gravity.

An independent check of the reference energies in VALIDATION.md and a
continuous curve to compare a run's conserved.csv with (the reference
gives four times only). G = M = R = 1, rho = 1/(2 pi r), u = 0.05,
gamma = 5/3, at rest; free outer surface.

Equal-mass shells (edges at r_k = sqrt(k/N), so M(<r) = r^2), velocities
on the edges, leapfrog in time, von Neumann-Richtmyer viscosity (quadratic
`cq`, linear `cl`) in compressing shells. With N = 2000 and CFL 0.05 the
energies at t = 0.8 / 1.0 / 2.0 / 3.0 land within 0.8% of VALIDATION.md's
and the total energy drifts by 0.8% through the bounce (about 20 s).

Usage: evrard_1d.py [N] [CFL] [--profile T]
Prints `t E_kin E_int E_grav E_tot` at the output times; with --profile,
also writes `r v rho u M` per shell at time T to evrard_1d_profile.txt.
"""
import sys

import numpy as np


def run(n=2000, cfl=0.05, cq=2.0, cl=0.3, profile_at=None):
    gamma = 5.0 / 3.0
    dm = 1.0 / n
    r = np.sqrt(np.arange(n + 1) / n)  # shell edges
    v = np.zeros(n + 1)  # edge velocities, half a step ahead of r
    u = np.full(n, 0.05)
    m_enc = np.arange(n + 1) * dm  # mass inside each edge
    m_edge = np.full(n + 1, dm)  # mass an edge moves
    m_edge[0] = m_edge[-1] = dm / 2

    def volume(r):
        return 4.0 * np.pi / 3.0 * (r[1:] ** 3 - r[:-1] ** 3)

    def e_grav(r):
        # -G int M dm / r, shell by shell at its mass midpoint
        r_mid = ((r[1:] ** 3 + r[:-1] ** 3) / 2) ** (1 / 3)
        return -np.sum((m_enc[1:] + m_enc[:-1]) / 2 * dm / r_mid)

    times = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95,
             1.0, 1.05, 1.1, 1.2, 1.3, 1.5, 1.8, 2.0, 2.5, 3.0]
    vol = volume(r)
    t, dt, k = 0.0, 1e-5, 0
    rows = []
    while k < len(times):
        rho = dm / vol
        c = np.sqrt(gamma * (gamma - 1) * u)
        dv = v[1:] - v[:-1]
        # Viscous pressure where the shell's volume shrinks (a shell whose
        # edges close in can still grow in volume as it moves out).
        dvol = r[1:] ** 2 * v[1:] - r[:-1] ** 2 * v[:-1]
        q = np.where((dv < 0) & (dvol < 0), cq * cq * rho * dv * dv - cl * rho * c * dv, 0.0)
        p = (gamma - 1) * rho * u + q
        dp = np.zeros(n + 1)
        dp[1:n] = p[1:] - p[:-1]
        dp[n] = -p[-1]  # vacuum outside
        acc = np.zeros(n + 1)
        acc[1:] = -4 * np.pi * r[1:] ** 2 * dp[1:] / m_edge[1:] - m_enc[1:] / r[1:] ** 2
        dt_new = min(cfl * np.min((r[1:] - r[:-1]) / (c + np.abs(dv) + 1e-30)), 1.2 * dt)
        dt_new = min(dt_new, times[k] - t)
        v = v + acc * 0.5 * (dt + dt_new)
        v[0] = 0.0
        dt = dt_new
        r_new = r + v * dt
        vol_new = volume(r_new)
        u = u - p * (vol_new - vol) / dm
        r, vol, t = r_new, vol_new, t + dt
        if abs(t - times[k]) < 1e-12:
            ek, ei, eg = 0.5 * np.sum(m_edge * v * v), np.sum(u) * dm, e_grav(r)
            rows.append((times[k], ek, ei, eg, ek + ei + eg))
            if profile_at is not None and abs(times[k] - profile_at) < 1e-9:
                np.savetxt("evrard_1d_profile.txt",
                           np.c_[r[1:], v[1:], dm / vol, u, m_enc[1:]],
                           header="r_outer v_outer rho u M_inside")
            k += 1
    return rows


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    prof = None
    if "--profile" in sys.argv:
        prof = float(sys.argv[sys.argv.index("--profile") + 1])
        args.remove(str(sys.argv[sys.argv.index("--profile") + 1]))
    n = int(args[0]) if args else 2000
    cfl = float(args[1]) if len(args) > 1 else 0.05
    print("t E_kin E_int E_grav E_tot")
    for row in run(n, cfl, profile_at=prof):
        print("%.2f %.4f %.4f %.4f %.4f" % row)
