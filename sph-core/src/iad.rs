//! The integral approach to derivatives (IAD): the matrix
//! `tau_i = sum_j V_j W(r_ij, h_i) (x_j - x_i) (x_j - x_i)^T` and its
//! inverse `C_i`, which turns kernel sums into gradients exact for linear
//! fields.

use crate::density::Positions;
use crate::geometry::{max_reach, Separation};
use crate::lanes::{F64s, GroupUnion, LANES};
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// A singular matrix found by [`iad`]: local index, determinant of the
/// normalised matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Singular {
    /// Local index of the particle.
    pub index: usize,
    /// Determinant of `tau` scaled to unit trace/3.
    pub det: f64,
}

/// Inverts a symmetric 3x3 matrix given as (xx, xy, xz, yy, yz, zz) by
/// cofactors, after scaling it by a power of two so that its mean diagonal
/// is near one (exact in binary, so the result is rescaled exactly).
/// Returns `None` when the normalised determinant is below `1e-10`.
#[inline]
pub fn invert_symmetric(t: [f64; 6]) -> Result<[f64; 6], f64> {
    let trace = (t[0] + t[3] + t[5]) / 3.0;
    if !(trace > 0.0 && trace.is_finite()) {
        return Err(0.0);
    }
    let e = trace.log2().round() as i32;
    let s = (-e as f64).exp2();
    let a = t.map(|v| v * s);
    let c00 = a[3] * a[5] - a[4] * a[4];
    let c01 = a[2] * a[4] - a[1] * a[5];
    let c02 = a[1] * a[4] - a[2] * a[3];
    let det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    if det.abs().is_nan() || det.abs() <= 1e-10 {
        return Err(det);
    }
    let c11 = a[0] * a[5] - a[2] * a[2];
    let c12 = a[1] * a[2] - a[0] * a[4];
    let c22 = a[0] * a[3] - a[1] * a[1];
    let f = s / det;
    Ok([c00 * f, c01 * f, c02 * f, c11 * f, c12 * f, c22 * f])
}

/// Fills the six components of `C_i = tau_i^{-1}` for every target, with
/// volumes `V_j = m_j / rho_j`. Returns the lowest-index singular matrix,
/// if any (its components are left as zeros).
pub fn iad<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    rho: &[f64],
    nl: &CompactNeighborList,
    c: &mut [Vec<f64>; 6],
) -> Result<(), Singular> {
    let sep = Separation::new(bbox);
    let reach = max_reach(kernel.support(), pos.h);
    let targets = nl.targets();
    let norm = kernel.norm();
    let n = pos.x.len();
    let (x, y, z, m, rho) = (
        &pos.x[..n],
        &pos.y[..n],
        &pos.z[..n],
        &pos.m[..n],
        &rho[..n],
    );
    let [c0, c1, c2, c3, c4, c5] = c;
    let range = targets.clone();
    // Targets in groups of LANES over the union of their lists: partners
    // beyond 2 h_i add W = 0, so each lane is the scalar sum over its list.
    let bad = (
        c0[range.clone()].par_chunks_mut(LANES),
        c1[range.clone()].par_chunks_mut(LANES),
        c2[range.clone()].par_chunks_mut(LANES),
        c3[range.clone()].par_chunks_mut(LANES),
        c4[range.clone()].par_chunks_mut(LANES),
        c5[range].par_chunks_mut(LANES),
    )
        .into_par_iter()
        .enumerate()
        .map_init(GroupUnion::default, |union, (g, out)| {
            let first = targets.start + g * LANES;
            let valid = out.0.len();
            let load = |a: &[f64]| F64s::load(a, first, valid);
            let xi = [load(x), load(y), load(z)];
            let sep = sep.for_group(xi, reach);
            let inv_h = 1.0 / load(pos.h);
            let mut t = [F64s::splat(0.0); 6];
            for run in union.build(nl, first..first + valid) {
                assert!(run.end <= n, "neighbour {} of {n} particles", run.end - 1);
                for j in run.clone() {
                    let d = sep.between_lanes(xi, [x[j], y[j], z[j]]);
                    let v = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * inv_h;
                    let w = m[j] / rho[j] * F64s::from_array(kernel.shape_lanes(&v.to_array()));
                    t[0] += w * d[0] * d[0];
                    t[1] += w * d[0] * d[1];
                    t[2] += w * d[0] * d[2];
                    t[3] += w * d[1] * d[1];
                    t[4] += w * d[1] * d[2];
                    t[5] += w * d[2] * d[2];
                }
            }
            let k3 = norm * inv_h * inv_h * inv_h;
            let t = t.map(|v| (v * k3).to_array());
            let mut out = [out.0, out.1, out.2, out.3, out.4, out.5];
            let mut first_bad = None;
            for l in 0..valid {
                let tl = [t[0][l], t[1][l], t[2][l], t[3][l], t[4][l], t[5][l]];
                let inv = invert_symmetric(tl).unwrap_or_else(|det| {
                    first_bad = first_bad.or(Some(Singular {
                        index: first + l,
                        det,
                    }));
                    [0.0; 6]
                });
                for (o, v) in out.iter_mut().zip(inv) {
                    o[l] = v;
                }
            }
            first_bad
        })
        .flatten()
        .min_by_key(|s| s.index);
    match bad {
        Some(s) => Err(s),
        None => Ok(()),
    }
}
