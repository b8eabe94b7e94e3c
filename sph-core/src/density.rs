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
    let omega = (!omega.is_empty()).then(|| [&mut omega[targets.clone()]]);
    let stage = Density {
        kernel,
        norm: kernel.norm(),
        h: pos.h,
        m: &pos.m[..pos.x.len()],
    };
    driver.run(&stage, ([&mut rho[targets]], omega));
}

/// The density sums: partners beyond 2 h_i add W = 0, so each lane is the
/// scalar sum over its list.
struct Density<'a, K> {
    kernel: &'a K,
    norm: f64,
    h: &'a [f64],
    m: &'a [f64],
}

impl<K: Kernel> PairStage for Density<'_, K> {
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
        let v = r2.sqrt() * *inv_h;
        let (w, dw) = self.kernel.shape_and_derivative_lanes(v);
        *sum_w += self.m[j] * w;
        *sum_dh += self.m[j] * (3.0 * w + v * dw);
    }

    #[inline(always)]
    fn finish(&self, _: &Group, (inv_h, sum_w, sum_dh): Self::Sums, out: Self::Out<'_>) {
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
