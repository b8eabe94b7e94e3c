//! Conserved quantities, summed exactly ([`ExactSum`]) so that the result
//! is the same bits whatever the number of threads or ranks.

use crate::Particles;
use rayon::prelude::*;
use sph_comm::{Communicator, ExactSum};
use std::ops::Range;

/// Particles per partial sum (one set of accumulators per chunk).
const CHUNK: usize = 4096;
/// Sums per particle: mass, E_kin, E_int, momentum (3), angular momentum
/// (3), E_grav.
const SUMS: usize = 10;

/// Totals over all particles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Conserved {
    /// Total mass.
    pub mass: f64,
    /// Kinetic energy `sum m v^2 / 2`.
    pub e_kin: f64,
    /// Internal energy `sum m u`.
    pub e_int: f64,
    /// Gravitational energy `sum m phi / 2` (zero without self-gravity).
    pub e_grav: f64,
    /// Linear momentum.
    pub momentum: [f64; 3],
    /// Angular momentum about the origin, `sum m x × v`.
    pub angular_momentum: [f64; 3],
}

impl Conserved {
    /// Total energy (kinetic + internal + gravitational).
    pub fn e_tot(&self) -> f64 {
        self.e_kin + self.e_int + self.e_grav
    }

    /// Sums over the `owned` particles of `p` on every rank of `comm`, plus
    /// the rank's `extra` values (summed exactly as well, returned reduced):
    /// one all-reduce in all.
    pub fn compute<C: Communicator, const E: usize>(
        p: &Particles,
        owned: Range<usize>,
        extra: [f64; E],
        comm: &C,
    ) -> (Self, [f64; E]) {
        let (c, extra, []) = Self::compute_with(p, owned, extra, [], comm);
        (c, extra)
    }

    /// As [`compute`](Self::compute), with the rank's exact partial sums
    /// `sums` (of per-particle terms, so that their totals do not depend on
    /// the rank count) reduced in the same all-reduce.
    pub fn compute_with<C: Communicator, const E: usize, const S: usize>(
        p: &Particles,
        owned: Range<usize>,
        extra: [f64; E],
        sums_in: [ExactSum; S],
        comm: &C,
    ) -> (Self, [f64; E], [f64; S]) {
        let with_phi = !p.phi.is_empty();
        let o = owned.start;
        let sums: [ExactSum; SUMS] = exact_sums(owned.len(), |k, s: &mut [ExactSum; SUMS]| {
            let i = o + k;
            let m = p.m[i];
            let v = [p.vx[i], p.vy[i], p.vz[i]];
            let x = [p.x[i], p.y[i], p.z[i]];
            s[0].add(m);
            s[1].add(0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
            s[2].add(m * p.u[i]);
            for k in 0..3 {
                s[3 + k].add(m * v[k]);
            }
            s[6].add(m * (x[1] * v[2] - x[2] * v[1]));
            s[7].add(m * (x[2] * v[0] - x[0] * v[2]));
            s[8].add(m * (x[0] * v[1] - x[1] * v[0]));
            if with_phi {
                s[9].add(0.5 * m * p.phi[i]);
            }
        });
        let mut sums: Vec<ExactSum> = sums.into_iter().collect();
        sums.extend(
            extra
                .iter()
                .map(|&e| std::iter::once(e).collect::<ExactSum>()),
        );
        sums.extend(sums_in);
        ExactSum::all_reduce_many(&mut sums, comm);
        let v: Vec<f64> = sums.iter().map(ExactSum::value).collect();
        let c = Conserved {
            mass: v[0],
            e_kin: v[1],
            e_int: v[2],
            e_grav: v[9],
            momentum: [v[3], v[4], v[5]],
            angular_momentum: [v[6], v[7], v[8]],
        };
        (
            c,
            std::array::from_fn(|k| v[SUMS + k]),
            std::array::from_fn(|k| v[SUMS + E + k]),
        )
    }
}

/// Exact sums of `terms(i, sums)` over `0..n`, in parallel chunks (the
/// totals do not depend on the chunking).
pub(crate) fn exact_sums<const S: usize>(
    n: usize,
    terms: impl Fn(usize, &mut [ExactSum; S]) + Sync,
) -> [ExactSum; S] {
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut s: [ExactSum; S] = std::array::from_fn(|_| ExactSum::new());
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                terms(i, &mut s);
            }
            s
        })
        .reduce(
            || std::array::from_fn(|_| ExactSum::new()),
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b.iter()) {
                    x.merge(y);
                }
                a
            },
        )
}
