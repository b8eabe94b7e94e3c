//! Artificial conductivity of internal energy (Price 2008): a diffusion of
//! `u` across pressure jumps that smooths the spurious entropy spikes
//! viscosity leaves at shocks and walls ("wall heating" in the Noh test).
//!
//! ```text
//! du_i/dt += sum_j m_j alpha_u v_u (u_i - u_j) / rho_ij * (W'(r, h_i) + W'(r, h_j)) / 2
//! v_u = sqrt(|P_i - P_j| / rho_ij),   rho_ij = (rho_i + rho_j) / 2,
//! ```
//!
//! with `W'(r, h) = dW/dr <= 0`, so heat flows from hot to cold. The pair
//! term is antisymmetric: `sum_i m_i du_i/dt` is unchanged (total energy
//! conserved to round-off). A separate pass over the lists, run only when
//! the conductivity is on, after the momentum stage.

use crate::density::Positions;
use crate::geometry::Separation;
use rayon::prelude::*;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// Adds the conductive heating rate to `du` for every target of `nl`
/// (neighbours in ascending order: independent of the thread count).
/// `rho`, `p` and `u` must cover every particle the lists reach.
///
/// ```
/// use sph_core::conduction::conduction;
/// use sph_core::density::Positions;
/// use sph_kernels::{CubicSpline, Kernel};
/// use sph_tree::{compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve};
/// use sph_tree::{NeighborSearch, Octree};
///
/// // Two particles 0.5 apart, the left one hotter and at higher pressure.
/// let (x, y, z) = (vec![0.25, 0.75], vec![0.5; 2], vec![0.5; 2]);
/// let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
/// let mut keys = Vec::new();
/// compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
/// let (x, y, z, keys) = if keys[0] <= keys[1] {
///     (x, y, z, keys)
/// } else {
///     (vec![0.75, 0.25], y, z, vec![keys[1], keys[0]])
/// };
/// let tree = Octree::build(&keys, &x, &y, &z, 4).unwrap();
/// let h = vec![0.4; 2];
/// let mut list = CompactNeighborList::new();
/// NeighborSearch::default().find_compact(&tree, &bbox, &x, &y, &z, &h, 0..2, &mut list).unwrap();
/// let m = vec![1.0; 2];
/// let pos = Positions { x: &x, y: &y, z: &z, h: &h, m: &m };
/// let hot = if x[0] < 0.5 { 0 } else { 1 };
/// let mut u = vec![1.0; 2];
/// let mut p = vec![1.0; 2];
/// u[hot] = 2.0;
/// p[hot] = 2.0;
/// let mut du = vec![0.0; 2];
/// conduction(&CubicSpline, &bbox, pos, &[1.0; 2], &p, &u, 1.0, &list, &mut du);
/// assert!(du[hot] < 0.0 && du[1 - hot] > 0.0);
/// assert!((du[0] + du[1]).abs() < 1e-15); // equal masses: energy kept
/// ```
#[allow(clippy::too_many_arguments)]
pub fn conduction<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    rho: &[f64],
    p: &[f64],
    u: &[f64],
    alpha_u: f64,
    nl: &CompactNeighborList,
    du: &mut [f64],
) {
    let sep = Separation::new(bbox);
    let targets = nl.targets();
    let norm = kernel.norm();
    du[targets.clone()]
        .par_iter_mut()
        .enumerate()
        .for_each(|(k, du_i)| {
            let i = targets.start + k;
            let pi = [pos.x[i], pos.y[i], pos.z[i]];
            let inv_hi = 1.0 / pos.h[i];
            let ki4 = norm * inv_hi.powi(4);
            let mut sum = 0.0;
            for run in nl.runs(i) {
                for j in run {
                    if j == i {
                        continue;
                    }
                    let d = sep.between(pi, [pos.x[j], pos.y[j], pos.z[j]]);
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let inv_hj = 1.0 / pos.h[j];
                    let kj4 = norm * inv_hj.powi(4);
                    let dw = 0.5
                        * (ki4 * kernel.shape_derivative(r * inv_hi)
                            + kj4 * kernel.shape_derivative(r * inv_hj));
                    let rho_ij = 0.5 * (rho[i] + rho[j]);
                    let v_u = ((p[i] - p[j]).abs() / rho_ij).sqrt();
                    sum += pos.m[j] * v_u * (u[i] - u[j]) / rho_ij * dw;
                }
            }
            *du_i += alpha_u * sum;
        });
}
