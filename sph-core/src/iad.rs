//! The integral approach to derivatives (IAD): the matrix
//! `tau_i = sum_j V_j W(r_ij, h_i) (x_j - x_i) (x_j - x_i)^T` and its
//! inverse `C_i`, which turns kernel sums into gradients exact for linear
//! fields.

use crate::density::Positions;
use crate::geometry::Separation;
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
    let targets = nl.targets();
    let norm = kernel.norm();
    let [c0, c1, c2, c3, c4, c5] = c;
    let range = targets.clone();
    let bad = (
        c0[range.clone()].par_iter_mut(),
        c1[range.clone()].par_iter_mut(),
        c2[range.clone()].par_iter_mut(),
        c3[range.clone()].par_iter_mut(),
        c4[range.clone()].par_iter_mut(),
        c5[range].par_iter_mut(),
    )
        .into_par_iter()
        .enumerate()
        .filter_map(|(k, out)| {
            let i = targets.start + k;
            let pi = [pos.x[i], pos.y[i], pos.z[i]];
            let inv_h = 1.0 / pos.h[i];
            let mut t = [0.0; 6];
            for run in nl.runs(i) {
                for j in run {
                    let d = sep.between(pi, [pos.x[j], pos.y[j], pos.z[j]]);
                    let v = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * inv_h;
                    let w = pos.m[j] / rho[j] * kernel.shape(v);
                    t[0] += w * d[0] * d[0];
                    t[1] += w * d[0] * d[1];
                    t[2] += w * d[0] * d[2];
                    t[3] += w * d[1] * d[1];
                    t[4] += w * d[1] * d[2];
                    t[5] += w * d[2] * d[2];
                }
            }
            let k3 = norm * inv_h * inv_h * inv_h;
            let t = t.map(|v| v * k3);
            match invert_symmetric(t) {
                Ok(inv) => {
                    *out.0 = inv[0];
                    *out.1 = inv[1];
                    *out.2 = inv[2];
                    *out.3 = inv[3];
                    *out.4 = inv[4];
                    *out.5 = inv[5];
                    None
                }
                Err(det) => {
                    *out.0 = 0.0;
                    *out.1 = 0.0;
                    *out.2 = 0.0;
                    *out.3 = 0.0;
                    *out.4 = 0.0;
                    *out.5 = 0.0;
                    Some(Singular { index: i, det })
                }
            }
        })
        .min_by_key(|s| s.index);
    match bad {
        Some(s) => Err(s),
        None => Ok(()),
    }
}
