//! The integral approach to derivatives (IAD): the matrix
//! `tau_i = sum_j V_j W(r_ij, h_i) (x_j - x_i) (x_j - x_i)^T` and its
//! inverse `C_i`, which turns kernel sums into gradients exact for linear
//! fields.

use crate::density::Positions;
use crate::pair_loop::{F64s, Group, PairLoop, PairStage, Reduce, LANES};
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
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
pub fn iad<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    rho: &[f64],
    nl: &CompactNeighborList,
    c: &mut [Vec<f64>; 6],
) -> Result<(), Singular> {
    iad_volumes(kernel, bbox, pos, [pos.m, rho], nl, c)
}

/// As [`iad`] with volumes `V_j = num_j / den_j` given as the pair
/// `[num, den]`: `[m, rho]` is [`iad`]; the generalised volume elements
/// pass `[X, k]` ([`ve_density`](crate::density::ve_density)).
///
/// # Errors
/// The lowest-index singular matrix, as [`iad`].
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
pub fn iad_volumes<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    [num, den]: [&[f64]; 2],
    nl: &CompactNeighborList,
    c: &mut [Vec<f64>; 6],
) -> Result<(), Singular> {
    let driver = PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
        .expect("iad: positions");
    let n = pos.x.len();
    let stage = Tau {
        kernel,
        norm: kernel.norm(),
        h: pos.h,
        m: &num[..n],
        rho: &den[..n],
    };
    let r = nl.targets();
    let [c0, c1, c2, c3, c4, c5] = c;
    let out = [c0, c1, c2, c3, c4, c5].map(|c| &mut c[r.clone()]);
    match driver.run(&stage, out) {
        FirstSingular(Some(s)) => Err(s),
        FirstSingular(None) => Ok(()),
    }
}

/// Writes the group's matrices into the six component slices.
#[inline(always)]
pub(crate) fn store_matrices(g: &Group, c: &[[f64; 6]; LANES], out: &mut [&mut [f64]; 6]) {
    for (l, cl) in c.iter().enumerate().take(g.valid) {
        for (o, &v) in out.iter_mut().zip(cl) {
            o[l] = v;
        }
    }
}

/// The lowest-index singular matrix of some targets.
pub(crate) struct FirstSingular(pub(crate) Option<Singular>);

impl Reduce for FirstSingular {
    fn identity() -> Self {
        Self(None)
    }

    fn merge(self, o: Self) -> Self {
        match (self.0, o.0) {
            (Some(a), Some(b)) => Self(Some(if a.index <= b.index { a } else { b })),
            (a, b) => Self(a.or(b)),
        }
    }
}

/// The sums of `tau`: partners beyond 2 h_i add W = 0, so each lane is the
/// scalar sum over its list.
pub(crate) struct Tau<'a, K> {
    pub(crate) kernel: &'a K,
    pub(crate) norm: f64,
    pub(crate) h: &'a [f64],
    /// Volume numerators (`m` or `X`).
    pub(crate) m: &'a [f64],
    /// Volume denominators (`rho` or `k`).
    pub(crate) rho: &'a [f64],
}

/// A group's `1/h` and six sums of `tau`.
pub(crate) type TauSums = (F64s, [F64s; 6]);

impl<K: Kernel> Tau<'_, K> {
    /// Adds partner `j` at separation `d` with kernel shape `shape`.
    #[inline(always)]
    pub(crate) fn add(&self, t: &mut [F64s; 6], j: usize, d: [F64s; 3], shape: F64s) {
        let w = self.m[j] / self.rho[j] * shape;
        t[0] += w * d[0] * d[0];
        t[1] += w * d[0] * d[1];
        t[2] += w * d[0] * d[2];
        t[3] += w * d[1] * d[1];
        t[4] += w * d[1] * d[2];
        t[5] += w * d[2] * d[2];
    }

    /// The group's inverse matrices per lane (zeros where singular) and
    /// the first singular one.
    #[inline(always)]
    pub(crate) fn invert(
        &self,
        g: &Group,
        (inv_h, t): TauSums,
    ) -> ([[f64; 6]; LANES], FirstSingular) {
        let k3 = self.norm * inv_h * inv_h * inv_h;
        let t = t.map(|v| (v * k3).to_array());
        let mut first_bad = None;
        let mut c = [[0.0; 6]; LANES];
        for (l, cl) in c.iter_mut().enumerate().take(g.valid) {
            let tl = [t[0][l], t[1][l], t[2][l], t[3][l], t[4][l], t[5][l]];
            *cl = invert_symmetric(tl).unwrap_or_else(|det| {
                first_bad = first_bad.or(Some(Singular {
                    index: g.first + l,
                    det,
                }));
                [0.0; 6]
            });
        }
        (c, FirstSingular(first_bad))
    }
}

impl<K: Kernel> PairStage for Tau<'_, K> {
    /// `1/h` and the six components of `tau`.
    type Sums = (F64s, [F64s; 6]);
    type Out<'o> = [&'o mut [f64]; 6];
    type Stats = FirstSingular;

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        (1.0 / g.load(self.h), [F64s::splat(0.0); 6])
    }

    #[inline(always)]
    fn pair(&self, (inv_h, t): &mut Self::Sums, j: usize, d: [F64s; 3], r2: F64s) {
        let v2 = r2 * (*inv_h * *inv_h);
        self.add(t, j, d, self.kernel.shape_sq_lanes(v2));
    }

    #[inline(always)]
    fn finish(&self, g: &Group, sums: Self::Sums, out: &mut Self::Out<'_>) -> FirstSingular {
        let (c, first_bad) = self.invert(g, sums);
        store_matrices(g, &c, out);
        first_bad
    }
}
