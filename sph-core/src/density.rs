//! Density by kernel summation and the grad-h factor Omega.

use crate::pair_loop::{F64s, Group, PairLoop, PairStage};
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
///
/// # Panics
/// If the position arrays differ in length or do not cover the lists.
pub fn density<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    nl: &CompactNeighborList,
    rho: &mut [f64],
    omega: &mut [f64],
) {
    let driver = PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
        .expect("density: positions");
    let targets = nl.targets();
    let m = &pos.m[..pos.x.len()];
    let (norm, h) = (kernel.norm(), pos.h);
    if omega.is_empty() {
        let stage = Density::<K, false> { kernel, norm, h, m };
        driver.run(&stage, ([&mut rho[targets]], None));
    } else {
        let stage = Density::<K, true> { kernel, norm, h, m };
        driver.run(
            &stage,
            ([&mut rho[targets.clone()]], Some([&mut omega[targets]])),
        );
    }
}

/// The density sums: partners beyond 2 h_i add W = 0, so each lane is the
/// scalar sum over its list. Without `GRAD_H` the kernel derivative is not
/// evaluated (the density bits are the same either way).
struct Density<'a, K, const GRAD_H: bool> {
    kernel: &'a K,
    norm: f64,
    h: &'a [f64],
    m: &'a [f64],
}

impl<K: Kernel, const GRAD_H: bool> PairStage for Density<'_, K, GRAD_H> {
    /// `1/h`, `sum m W`, `sum m (3 w + v w')`.
    type Sums = (F64s, F64s, F64s);
    type Out<'o> = ([&'o mut [f64]; 1], Option<[&'o mut [f64]; 1]>);
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        let zero = F64s::splat(0.0);
        (1.0 / g.load(self.h), zero, zero)
    }

    #[inline(always)]
    fn pair(&self, (inv_h, sum_w, sum_dh): &mut Self::Sums, j: usize, _: [F64s; 3], r2: F64s) {
        let v2 = r2 * (*inv_h * *inv_h);
        if GRAD_H {
            let (w, vdw) = self.kernel.shape_and_v_derivative_sq_lanes(v2);
            *sum_w += self.m[j] * w;
            *sum_dh += self.m[j] * (3.0 * w + vdw);
        } else {
            *sum_w += self.m[j] * self.kernel.shape_sq_lanes(v2);
        }
    }

    #[inline(always)]
    fn finish(&self, _: &Group, (inv_h, sum_w, sum_dh): Self::Sums, out: &mut Self::Out<'_>) {
        let h3 = inv_h * inv_h * inv_h;
        let rho_g = self.norm * h3 * sum_w;
        let ([rho], omega) = out;
        rho_g.store(rho);
        if let Some([o]) = omega {
            // dW/dh = -K/h^4 (3 w + v w'), so h/(3 rho) sum m dW/dh is:
            (1.0 - self.norm * h3 * sum_dh / (3.0 * rho_g)).store(o);
        }
    }
}

/// The generalised volume elements of SPH-EXA's "ve" scheme, first pass:
/// `X_i = m_i / rho0_i` for every target of `nl`, with the standard
/// density `rho0_i = sum_j m_j W(r_ij, h_i)` (self included). The halos'
/// `X` must be exchanged before [`ve_density`].
///
/// # Panics
/// If the position arrays differ in length or do not cover the lists.
pub fn xmass<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    nl: &CompactNeighborList,
    xm: &mut [f64],
) {
    density(kernel, bbox, pos, nl, xm, &mut []);
    for i in nl.served_targets() {
        xm[i] = pos.m[i] / xm[i];
    }
}

/// Where [`ve_density`] writes (slices over all particles; the targets'
/// entries are written).
#[derive(Debug)]
pub struct VeOut<'a> {
    /// The normalisation `k_i`.
    pub kx: &'a mut [f64],
    /// The density `rho_i = k_i m_i / X_i`.
    pub rho: &'a mut [f64],
    /// The grad-h factor (empty: not computed).
    pub omega: &'a mut [f64],
}

/// The generalised volume elements, second pass, for every target of
/// `nl` (`xm` from [`xmass`], halos included):
///
/// ```text
/// k_i     = sum_j X_j W(r_ij, h_i)                       (self included)
/// rho_i   = k_i m_i / X_i
/// Omega_i = 1 + h_i / (3 rho_i) [ (m_i / X_i) sum_j X_j dW/dh(r_ij, h_i)
///                                 + (k_i - X_i W(0, h_i)) sum_j m_j dW/dh(r_ij, h_i) ]
/// ```
///
/// The bracket is SPH-EXA's `d rho_i / dh_i` (`ve_def_gradh`): the
/// derivative of `k_i m_i / X_i` with `d X_i / dh` entering through the
/// neighbours' part of `k_i` only. The volumes `V_j = X_j / k_j` make
/// `sum_j V_j W_ij` a partition of unity to the accuracy of the kernel
/// sums; the IAD matrices are built with them
/// ([`iad_volumes`](crate::iad::iad_volumes)).
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
pub fn ve_density<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    xm: &[f64],
    nl: &CompactNeighborList,
    out: VeOut<'_>,
) {
    volume_density(kernel, bbox, pos, xm, true, nl, out);
}

/// As [`ve_density`] for pressure-energy volume elements `X_j = m_j u_j`
/// (halos included), which do not depend on h: the grad-h factor is
/// `Omega_i = 1 + h_i / (3 rho_i) (m_i / X_i) sum_j X_j dW/dh(r_ij, h_i)`,
/// the derivative of `k_i m_i / X_i` through `k_i` alone.
///
/// ```
/// use sph_core::density::{pressure_energy_density, Positions, VeOut};
/// use sph_kernels::{CubicSpline, Kernel};
/// use sph_tree::{compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve};
/// use sph_tree::{NeighborSearch, Octree};
///
/// // Two particles 0.5 apart, m = 1, one with u = 1 and one with u = 8.
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
/// let (h, m) = (vec![0.4; 2], vec![1.0; 2]);
/// let mut list = CompactNeighborList::new();
/// NeighborSearch::default().find_compact(&tree, &bbox, &x, &y, &z, &h, 0..2, &mut list).unwrap();
/// let xm = [1.0, 8.0]; // X = m u
/// let (mut kx, mut rho, mut omega) = ([0.0; 2], [0.0; 2], [0.0; 2]);
/// let pos = Positions { x: &x, y: &y, z: &z, h: &h, m: &m };
/// let out = VeOut { kx: &mut kx, rho: &mut rho, omega: &mut omega };
/// pressure_energy_density(&CubicSpline, &bbox, pos, &xm, &list, out);
/// // k_i = sum_j X_j W(r_ij, h_i) (self included), rho_i = k_i m_i / X_i.
/// let w = |r: f64| CubicSpline.w(r, 0.4);
/// for (i, j) in [(0, 1), (1, 0)] {
///     let k = xm[i] * w(0.0) + xm[j] * w(0.5);
///     assert!((kx[i] - k).abs() < 1e-12 * k);
///     assert!((rho[i] - k * m[i] / xm[i]).abs() < 1e-12 * rho[i]);
/// }
/// ```
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
pub fn pressure_energy_density<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    xm: &[f64],
    nl: &CompactNeighborList,
    out: VeOut<'_>,
) {
    volume_density(kernel, bbox, pos, xm, false, nl, out);
}

/// `k`, the density and Omega of volume elements `xm`; `x_of_h`: `X_i`
/// depends on `h_i` as SPH-EXA's `m_i / rho0_i` does.
fn volume_density<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    xm: &[f64],
    x_of_h: bool,
    nl: &CompactNeighborList,
    out: VeOut<'_>,
) {
    let driver = PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
        .expect("ve density: positions");
    let n = pos.x.len();
    let targets = nl.targets();
    let (norm, w0, h, m, xm) = (
        kernel.norm(),
        kernel.shape(0.0),
        pos.h,
        &pos.m[..n],
        &xm[..n],
    );
    let kx_rho = [&mut out.kx[targets.clone()], &mut out.rho[targets.clone()]];
    if out.omega.is_empty() {
        let stage = VeDensity::<K, false> {
            kernel,
            norm,
            w0,
            h,
            m,
            xm,
            x_of_h,
        };
        driver.run(&stage, (kx_rho, None));
    } else {
        let stage = VeDensity::<K, true> {
            kernel,
            norm,
            w0,
            h,
            m,
            xm,
            x_of_h,
        };
        driver.run(&stage, (kx_rho, Some([&mut out.omega[targets]])));
    }
}

/// The sums of the volume-element normalisation and, with `GRAD_H`, its
/// h-derivative.
struct VeDensity<'a, K, const GRAD_H: bool> {
    kernel: &'a K,
    norm: f64,
    /// The kernel shape at 0 (1 for the sinc family).
    w0: f64,
    h: &'a [f64],
    m: &'a [f64],
    xm: &'a [f64],
    /// Whether `X_i` depends on `h_i` (through the standard density).
    x_of_h: bool,
}

impl<K: Kernel, const GRAD_H: bool> PairStage for VeDensity<'_, K, GRAD_H> {
    /// `1/h`, `sum X w`, `sum X (3 w + v w')`, `sum m (3 w + v w')`.
    type Sums = (F64s, F64s, F64s, F64s);
    type Out<'o> = ([&'o mut [f64]; 2], Option<[&'o mut [f64]; 1]>);
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        let zero = F64s::splat(0.0);
        (1.0 / g.load(self.h), zero, zero, zero)
    }

    #[inline(always)]
    fn pair(&self, (inv_h, sk, sx, sm): &mut Self::Sums, j: usize, _: [F64s; 3], r2: F64s) {
        let v2 = r2 * (*inv_h * *inv_h);
        if GRAD_H {
            let (w, vdw) = self.kernel.shape_and_v_derivative_sq_lanes(v2);
            let dh = 3.0 * w + vdw;
            *sk += self.xm[j] * w;
            *sx += self.xm[j] * dh;
            *sm += self.m[j] * dh;
        } else {
            *sk += self.xm[j] * self.kernel.shape_sq_lanes(v2);
        }
    }

    #[inline(always)]
    fn finish(&self, g: &Group, (inv_h, sk, sx, sm): Self::Sums, out: &mut Self::Out<'_>) {
        let h3 = self.norm * inv_h * inv_h * inv_h;
        let (xi, mi) = (g.load(self.xm), g.load(self.m));
        let kx = h3 * sk;
        let rho = kx * mi / xi;
        let ([k_out, rho_out], omega) = out;
        kx.store(k_out);
        rho.store(rho_out);
        if let Some([o]) = omega {
            // dW/dh = -K/h^4 (3 w + v w'); the self term of k is K w(0) X_i / h^3.
            let h4 = h3 * inv_h;
            let mut drho_dh = -(h4 * sx) * mi / xi;
            if self.x_of_h {
                drho_dh -= (kx - h3 * self.w0 * xi) * (h4 * sm);
            }
            (1.0 + drho_dh / (3.0 * rho * inv_h)).store(o);
        }
    }
}
