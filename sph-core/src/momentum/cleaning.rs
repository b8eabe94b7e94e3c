//! SPH-EXA's "AV cleaning" of the viscosity's velocity jump.

use crate::pair_loop::{sym_mat_vec, F64s, Group};

/// SPH-EXA's "AV cleaning": the viscosity of pair `i, j` sees the
/// velocity jump left after a linear reconstruction from both sides,
/// `r . v_ij - phi_ij (r . G_i r + r . G_j r)` instead of `r . v_ij`,
/// with `G` the symmetric velocity gradient, `r = x_i - x_j` and the
/// van Leer type limiter
///
/// ```text
/// A = (r . G_i r) / (r . G_j r),   phi_ij = 1/2 damp(eta) clamp(4 A / (1 + A)^2, 0, 1)
/// ```
///
/// evaluated as `phi_ij (q_i + q_j) = damp 2 q_i q_j / (q_i + q_j)` where
/// `q_i = r . G_i r` and `q_j` agree in sign, else 0 (the harmonic mean of
/// the two reconstructions: one division, and the same bits for `j, i`).
///
/// (`damp = exp(-(5 (eta - eta_c))^2)` for pairs closer than
/// `eta = min(r/h_i, r/h_j) < eta_c`, else 1; `eta_c` the lattice spacing
/// over h for the target neighbour count). A linear velocity field
/// (shear, uniform compression) gives `A = 1`, `phi = 1/2` and no
/// viscosity at all; across a shock the two sides' gradients differ and
/// the limiter restores the full jump. The corrected jump is symmetric in
/// `i, j`, so momentum and energy stay conserved.
///
/// Only approaching pairs (`r . v_ij < 0`) are viscous, as without the
/// cleaning; SPH-EXA also applies the viscosity where the reconstructed
/// jump approaches but the particles recede, and there the viscous
/// "heating" `Pi_ij v_ij . grad W` is negative: heat turns into bulk
/// motion, and a cold particle can be drained below u = 0 (Evrard 40^3
/// with `best` and the cleaning stopped so at t = 1.78). Leaving such
/// pairs alone costs the Kelvin-Helmholtz mode some growth (M(1.5) 0.074
/// -> 0.066 at 32^2 x 8, 0.120 -> 0.117 at 64^2 x 8).
#[derive(Debug, Clone, Copy)]
pub struct AvCleaning<'a> {
    /// `G_xx, G_xy, G_xz, G_yy, G_yz, G_zz` of every particle (targets
    /// and halos).
    pub grad_v: [&'a [f64]; 6],
    /// `eta_c`.
    pub eta_crit: f64,
}

impl AvCleaning<'_> {
    /// The spacing over h of a lattice with `ng0` neighbours within 2 h:
    /// `(32 pi / (3 (ng0 + 1)))^(1/3)` (SPH-EXA's `eta_crit`).
    ///
    /// ```
    /// let e = sph_core::momentum::AvCleaning::eta_crit(100);
    /// assert!((e - 0.6923).abs() < 1e-4);
    /// ```
    pub fn eta_crit(ng0: usize) -> f64 {
        (32.0 * std::f64::consts::PI / (3.0 * (ng0 as f64 + 1.0))).cbrt()
    }

    /// The targets' velocity gradients.
    #[inline(always)]
    pub(crate) fn target(&self, g: &Group) -> [F64s; 6] {
        self.grad_v.map(|f| g.load(f))
    }

    /// The additive correction to `r . v_ij` for partner `j` at separation
    /// `d = x_i - x_j`, from the targets' gradients `gi`, with
    /// `eta = min(r/h_i, r/h_j)`.
    #[inline(always)]
    pub(crate) fn correction(&self, gi: [F64s; 6], j: usize, d: [F64s; 3], eta: F64s) -> F64s {
        let zero = F64s::splat(0.0);
        let gj = self.grad_v.map(|g| F64s::splat(g[j]));
        let quad = |g: [F64s; 6]| {
            let gd = sym_mat_vec(&g, d);
            gd[0] * d[0] + gd[1] * d[1] + gd[2] * d[2]
        };
        let (qi, qj) = (quad(gi), quad(gj));
        // phi (qi + qj) with phi = clamp(4 A / (1 + A)^2, 0, 1) / 2, A = qi / qj,
        // is 2 qi qj / (qi + qj), the harmonic mean of the two sides'
        // reconstructions, where they agree in sign (AM-GM keeps 4 A / (1 + A)^2
        // within (0, 1] there), and 0 where they do not: one division, no clamp.
        let prod = qi * qj;
        let agree = prod.gt(zero);
        let mean = agree.select(2.0 * prod / agree.select(qi + qj, F64s::splat(1.0)), zero);
        let mut damp = F64s::splat(1.0);
        if eta.min_lane() < self.eta_crit {
            // Pairs closer than the spacing (rare): damped toward r = 0.
            let e = eta.to_array();
            damp = F64s::from_array(std::array::from_fn(|l| {
                if e[l] < self.eta_crit {
                    let x = 5.0 * (e[l] - self.eta_crit);
                    (-x * x).exp()
                } else {
                    1.0
                }
            }));
        }
        -(damp * mean)
    }
}
