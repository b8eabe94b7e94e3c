//! Density by kernel summation and the grad-h factor Omega.

use crate::geometry::Separation;
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// Positions, smoothing lengths and masses: what a kernel sum reads.
#[derive(Debug, Clone, Copy)]
pub struct Positions<'a> {
    /// x coordinates.
    pub x: &'a [f64],
    /// y coordinates.
    pub y: &'a [f64],
    /// z coordinates.
    pub z: &'a [f64],
    /// Smoothing lengths.
    pub h: &'a [f64],
    /// Masses.
    pub m: &'a [f64],
}

/// `rho_i = sum_j m_j W(r_ij, h_i)` (self included) for every target of
/// `nl`, and, when `omega` is not empty,
/// `Omega_i = 1 + h_i / (3 rho_i) sum_j m_j dW/dh(r_ij, h_i)`.
/// Sums run over the neighbour list in ascending order, so the result does
/// not depend on the number of threads.
pub fn density<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    nl: &CompactNeighborList,
    rho: &mut [f64],
    omega: &mut [f64],
) {
    let sep = Separation::new(bbox);
    let targets = nl.targets();
    let norm = kernel.norm();
    let with_omega = !omega.is_empty();
    let one = |i: usize| -> (f64, f64) {
        let pi = [pos.x[i], pos.y[i], pos.z[i]];
        let hi = pos.h[i];
        let inv_h = 1.0 / hi;
        let mut sum_w = 0.0;
        let mut sum_dh = 0.0;
        for run in nl.runs(i) {
            for j in run {
                let d = sep.between(pi, [pos.x[j], pos.y[j], pos.z[j]]);
                let v = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * inv_h;
                let (w, dw) = kernel.shape_and_derivative(v);
                sum_w += pos.m[j] * w;
                sum_dh += pos.m[j] * (3.0 * w + v * dw);
            }
        }
        let h3 = inv_h * inv_h * inv_h;
        let r = norm * h3 * sum_w;
        // dW/dh = -K/h^4 (3 w + v w'), so h/(3 rho) sum m dW/dh is:
        let om = 1.0 - norm * h3 * sum_dh / (3.0 * r);
        (r, om)
    };
    let rho_t = &mut rho[targets.clone()];
    if with_omega {
        rho_t
            .par_iter_mut()
            .zip(omega[targets.clone()].par_iter_mut())
            .enumerate()
            .for_each(|(k, (r, o))| {
                let (a, b) = one(targets.start + k);
                *r = a;
                *o = b;
            });
    } else {
        rho_t
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, r)| *r = one(targets.start + k).0);
    }
}
