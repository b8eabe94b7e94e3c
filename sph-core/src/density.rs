//! Density by kernel summation and the grad-h factor Omega.

use crate::geometry::{max_reach, Separation};
use crate::lanes::{F64s, GroupUnion, LANES};
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
    let reach = max_reach(kernel.support(), pos.h);
    let targets = nl.targets();
    let norm = kernel.norm();
    let with_omega = !omega.is_empty();
    let n = pos.x.len();
    let (x, y, z, m) = (&pos.x[..n], &pos.y[..n], &pos.z[..n], &pos.m[..n]);
    // Targets in groups of LANES over the union of their lists: partners
    // beyond 2 h_i add W = 0, so each lane is the scalar sum over its list.
    let group = |union: &mut GroupUnion, g: usize, r: &mut [f64], o: Option<&mut [f64]>| {
        let first = targets.start + g * LANES;
        let valid = r.len();
        let load = |a: &[f64]| F64s::load(a, first, valid);
        let xi = [load(x), load(y), load(z)];
        let sep = sep.for_group(xi, reach);
        let inv_h = 1.0 / load(pos.h);
        let zero = F64s::splat(0.0);
        let (mut sum_w, mut sum_dh) = (zero, zero);
        for run in union.build(nl, first..first + valid) {
            assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
            for j in run.clone() {
                let d = sep.between_lanes(xi, [x[j], y[j], z[j]]);
                let v = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * inv_h;
                let (w, dw) = kernel.shape_and_derivative_lanes(&v.to_array());
                let (w, dw) = (F64s::from_array(w), F64s::from_array(dw));
                sum_w += m[j] * w;
                sum_dh += m[j] * (3.0 * w + v * dw);
            }
        }
        let h3 = inv_h * inv_h * inv_h;
        let rho_g = norm * h3 * sum_w;
        rho_g.store(r);
        if let Some(o) = o {
            // dW/dh = -K/h^4 (3 w + v w'), so h/(3 rho) sum m dW/dh is:
            (1.0 - norm * h3 * sum_dh / (3.0 * rho_g)).store(o);
        }
    };
    let rho_t = &mut rho[targets.clone()];
    if with_omega {
        rho_t
            .par_chunks_mut(LANES)
            .zip(omega[targets.clone()].par_chunks_mut(LANES))
            .enumerate()
            .for_each_init(GroupUnion::default, |u, (g, (r, o))| {
                group(u, g, r, Some(o))
            });
    } else {
        rho_t
            .par_chunks_mut(LANES)
            .enumerate()
            .for_each_init(GroupUnion::default, |u, (g, r)| group(u, g, r, None));
    }
}
