//! Exact O(N^2) direct summation, the reference for the tree code.
//!
//! Every pair `i != j` interacts with the same softening as the tree's
//! particle-particle interactions,
//! `r_eff^2 = max(r^2, (h_i + h_j)^2)` (no softening when `h` is `None`):
//!
//! ```text
//! a_i   =  G sum_{j != i} m_j (x_j - x_i) / r_eff^3
//! phi_i = -G sum_{j != i} m_j / r_eff * (3/2 - r^2 / (2 r_eff^2))
//! ```
//!
//! (the potential of a uniform sphere of radius `h_i + h_j` inside it, so
//! that the force is minus its gradient and energy is conserved; `-m/r`
//! outside).
//!
//! Coincident pairs with `r_eff = 0` (zero softening) add nothing. The
//! code is deliberately plain (one scalar loop per target, sources in index
//! order), independent of the tree's traversal and multipoles; the pair
//! formula is the tree's own (one function, so the two cannot drift
//! apart). Parallel over targets; the result does not depend on the thread
//! count.

use crate::pair::softened_p2p;
use crate::{validate, GravityError, GravityField};
use rayon::prelude::*;

/// Direct-sum accelerations and potentials of all particles, written into
/// `out` (resized). `g` is the gravitational constant.
///
/// ```
/// use sph_gravity::{direct, GravityField};
/// let mut out = GravityField::new();
/// direct::direct_sum(&[0.0, 2.0], &[0.0; 2], &[0.0; 2], &[1.0, 1.0], None, 1.0, &mut out)
///     .unwrap();
/// assert_eq!(out.ax, [0.25, -0.25]);
/// assert_eq!(out.phi, [-0.5, -0.5]);
/// ```
pub fn direct_sum(
    x: &[f64],
    y: &[f64],
    z: &[f64],
    m: &[f64],
    h: Option<&[f64]>,
    g: f64,
    out: &mut GravityField,
) -> Result<(), GravityError> {
    validate(x, y, z, m, h)?;
    if !g.is_finite() {
        return Err(GravityError::InvalidG(g));
    }
    let n = x.len();
    out.resize(n);
    let GravityField { ax, ay, az, phi } = out;
    (ax, ay, az, phi)
        .into_par_iter()
        .enumerate()
        .for_each(|(i, (ax, ay, az, phi))| {
            let (xi, yi, zi) = (x[i], y[i], z[i]);
            let hi = h.map_or(0.0, |h| h[i]);
            let (mut sx, mut sy, mut sz, mut sp) = (0.0, 0.0, 0.0, 0.0);
            for j in 0..n {
                if j == i {
                    continue;
                }
                let d = [x[j] - xi, y[j] - yi, z[j] - zi];
                let eps = h.map_or(0.0, |h| hi + h[j]);
                let (a, p) = softened_p2p::<true>(d, m[j], eps, true);
                sx += a[0];
                sy += a[1];
                sz += a[2];
                sp += p;
            }
            *ax = g * sx;
            *ay = g * sy;
            *az = g * sz;
            *phi = g * sp;
        });
    Ok(())
}
