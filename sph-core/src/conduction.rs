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
use crate::pair_loop::{F64s, Group, PairLoop, PairStage};
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
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
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
    let driver = PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
        .expect("conduction: positions");
    let stage = Conduction {
        kernel,
        norm: kernel.norm(),
        alpha_u,
        h: pos.h,
        m: pos.m,
        rho,
        p,
        u,
    };
    driver.run(&stage, [&mut du[nl.targets()]]);
}

/// The conduction sums: partners outside both supports (and the target
/// itself) add exact zeros.
struct Conduction<'a, K> {
    kernel: &'a K,
    norm: f64,
    alpha_u: f64,
    h: &'a [f64],
    m: &'a [f64],
    rho: &'a [f64],
    p: &'a [f64],
    u: &'a [f64],
}

/// A group's `1/h`, `K/h^4`, `rho`, `P`, `u` and the sum.
type ConductionSums = (F64s, F64s, F64s, F64s, F64s, F64s);

impl<K: Kernel> PairStage for Conduction<'_, K> {
    type Sums = ConductionSums;
    type Out<'o> = [&'o mut [f64]; 1];
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> ConductionSums {
        let inv_hi = 1.0 / g.load(self.h);
        let ih2 = inv_hi * inv_hi;
        let ki4 = self.norm * (ih2 * ih2);
        let (rho_i, p_i, u_i) = (g.load(self.rho), g.load(self.p), g.load(self.u));
        (inv_hi, ki4, rho_i, p_i, u_i, F64s::splat(0.0))
    }

    #[inline(always)]
    fn pair(&self, t: &mut ConductionSums, j: usize, _: [F64s; 3], r2: F64s) {
        let (inv_hi, ki4, rho_i, p_i, u_i, sum) = t;
        let r = r2.sqrt();
        let inv_hj = 1.0 / self.h[j];
        let kj4 = self.norm * inv_hj.powi(4);
        let wi = self.kernel.shape_and_derivative_lanes(r * *inv_hi).1;
        let wj = self.kernel.shape_and_derivative_lanes(r * inv_hj).1;
        let dw = 0.5 * (*ki4 * wi + kj4 * wj);
        let rho_ij = 0.5 * (*rho_i + self.rho[j]);
        let v_u = ((*p_i - self.p[j]).abs() / rho_ij).sqrt();
        *sum += self.m[j] * v_u * (*u_i - self.u[j]) / rho_ij * dw;
    }

    #[inline(always)]
    fn finish(&self, _: &Group, t: ConductionSums, [du]: Self::Out<'_>) {
        let add = (self.alpha_u * t.5).to_array();
        for (d, a) in du.iter_mut().zip(add) {
            *d += a;
        }
    }
}
