//! Conserved quantities, summed in a fixed order so that the result does
//! not depend on the number of threads.

use crate::Particles;
use rayon::prelude::*;

/// Particles per partial sum: partial sums are formed over fixed chunks and
/// then added in chunk order, independent of the thread count.
const CHUNK: usize = 4096;

/// Totals over all particles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Conserved {
    /// Total mass.
    pub mass: f64,
    /// Kinetic energy `sum m v^2 / 2`.
    pub e_kin: f64,
    /// Internal energy `sum m u`.
    pub e_int: f64,
    /// Linear momentum.
    pub momentum: [f64; 3],
    /// Angular momentum about the origin, `sum m x × v`.
    pub angular_momentum: [f64; 3],
}

impl Conserved {
    /// Total energy (kinetic + internal).
    pub fn e_tot(&self) -> f64 {
        self.e_kin + self.e_int
    }

    fn add(mut self, o: &Self) -> Self {
        self.mass += o.mass;
        self.e_kin += o.e_kin;
        self.e_int += o.e_int;
        for k in 0..3 {
            self.momentum[k] += o.momentum[k];
            self.angular_momentum[k] += o.angular_momentum[k];
        }
        self
    }

    /// Sums over the first `n_owned` particles of `p` (halos excluded).
    pub fn compute(p: &Particles, n_owned: usize) -> Self {
        let partial: Vec<Conserved> = (0..n_owned.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut s = Conserved::default();
                for i in c * CHUNK..((c + 1) * CHUNK).min(n_owned) {
                    let m = p.m[i];
                    let v = [p.vx[i], p.vy[i], p.vz[i]];
                    let x = [p.x[i], p.y[i], p.z[i]];
                    s.mass += m;
                    s.e_kin += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    s.e_int += m * p.u[i];
                    for k in 0..3 {
                        s.momentum[k] += m * v[k];
                    }
                    s.angular_momentum[0] += m * (x[1] * v[2] - x[2] * v[1]);
                    s.angular_momentum[1] += m * (x[2] * v[0] - x[0] * v[2]);
                    s.angular_momentum[2] += m * (x[0] * v[1] - x[1] * v[0]);
                }
                s
            })
            .collect();
        partial.iter().fold(Conserved::default(), |a, b| a.add(b))
    }
}
