//! Monaghan's (2000) artificial stress against the tensile instability.

use crate::pair_loop::F64s;
use sph_kernels::Kernel;

/// Monaghan's (2000) artificial stress for particles under tension: pair
/// `i, j` gains the repulsive term `R_ij f_ij^4` beside its pressure terms,
/// with `R_ij = R_i + R_j`, `R_i = epsilon max(-P_i, 0) / (Omega_i rho_i^2)`
/// and `f_ij = (w(r/h_i) + w(r/h_j)) / (2 w(q_s))`, `w` the kernel's shape
/// and `q_s` the particle spacing over h. It enters like a viscosity
/// term (force along the mean gradient, heating `1/2 R_ij f^4 v_ij . A`),
/// so momentum and energy stay conserved; it is zero where no pressure is
/// negative and falls off as `f^4` beyond the spacing, so it acts only on
/// pairs that close in under tension.
///
/// ```
/// use sph_core::momentum::ArtificialStress;
/// use sph_kernels::{Kernel, Sinc};
/// let k = Sinc::new(6.0).unwrap();
/// let s = ArtificialStress::new(0.2, 100, &k);
/// // The spacing of a lattice with 100 neighbours within 2 h is 0.694 h.
/// assert!((s.spacing_over_h - 0.6944).abs() < 1e-3);
/// assert!((s.inv_w_spacing * k.shape(s.spacing_over_h) - 1.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtificialStress {
    /// Strength `epsilon` (Monaghan 2000: 0.2 for `n = 4`).
    pub epsilon: f64,
    /// Spacing over smoothing length `q_s`: `2 (4 pi / (3 ng0))^(1/3)`
    /// for `ng0` neighbours within `2 h` of a lattice.
    pub spacing_over_h: f64,
    /// `1 / w(q_s)`.
    pub inv_w_spacing: f64,
}

impl ArtificialStress {
    /// The stress of strength `epsilon` for a target of `ng0` neighbours
    /// (self included) with `kernel`.
    pub fn new<K: Kernel>(epsilon: f64, ng0: usize, kernel: &K) -> Self {
        let spacing_over_h = 2.0 * (4.0 * std::f64::consts::PI / (3.0 * ng0 as f64)).cbrt();
        Self {
            epsilon,
            spacing_over_h,
            inv_w_spacing: 1.0 / kernel.shape(spacing_over_h),
        }
    }

    /// `R_i` of the targets from their pressure factors `P/(Omega rho^2)`.
    #[inline(always)]
    pub(crate) fn target(&self, pre_i: F64s) -> F64s {
        let zero = F64s::splat(0.0);
        F64s::splat(self.epsilon) * (zero - pre_i).max(zero)
    }

    /// The pair's `R_ij f^4 / 2` (added on each side), from the targets'
    /// `R_i`, the partner's pressure factor and both kernel shapes.
    #[inline(always)]
    pub(crate) fn pair(&self, r_i: F64s, pre_j: f64, shape_i: F64s, shape_j: F64s) -> F64s {
        let r_j = self.epsilon * (-pre_j).max(0.0);
        let f = 0.5 * self.inv_w_spacing * (shape_i + shape_j);
        let f2 = f * f;
        0.5 * (r_i + r_j) * f2 * f2
    }
}
