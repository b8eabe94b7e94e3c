//! Time integration: the second-order Press scheme for positions and
//! velocities, Adams-Bashforth 2 for internal energy, and the smoothing
//! length update towards the target neighbour count.
//!
//! With `dX_n = x_n - x_{n-1}` stored from the last step:
//! `v_n = dX_n / dt_{n-1} + a_n dt_{n-1} / 2`,
//! `dX_{n+1} = (v_n + a_n dt_n / 2) dt_n`, `x_{n+1} = x_n + dX_{n+1}`,
//! `v_{n+1} = v_n + a_n dt_n`, and
//! `u_{n+1} = u_n + du_n dt_n + (du_n - du_{n-1}) / dt_{n-1} dt_n^2 / 2`.

use crate::{CoreError, Particles};
use rayon::prelude::*;
use sph_tree::BoundingBox;
use std::ops::Range;

/// Smoothing-length update `h <- h * 0.5 * (1 + c ng0 / nc)^(1/p)`, whose
/// fixed point is `nc = ng0` (`docs/physics.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HUpdate {
    /// Target neighbour count (self included).
    pub ng0: f64,
    /// Constant `c`.
    pub c: f64,
    /// Exponent `p`.
    pub p: f64,
}

impl Default for HUpdate {
    fn default() -> Self {
        // SPH-EXA's current constants: 0.5 * 1024^(1/10) = 1 at nc = ng0,
        // and a gentle response (d ln h / d ln nc = -0.1) that does not
        // flip h between lattice shells every step, as the 2020 constants
        // (c = 7, p = 3) do.
        Self {
            ng0: 100.0,
            c: 1023.0,
            p: 10.0,
        }
    }
}

impl HUpdate {
    /// The factor applied to h for a particle with `nc` neighbours.
    #[inline]
    pub fn factor(&self, nc: u32) -> f64 {
        let nc = f64::from(nc.max(1));
        let base = 1.0 + self.c * self.ng0 / nc;
        0.5 * if self.p == 3.0 {
            base.cbrt()
        } else {
            base.powf(1.0 / self.p)
        }
    }
}

/// What integration observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IntegrateReport {
    /// Particles whose second-order energy update went negative and fell
    /// back to first order.
    pub energy_fallbacks: usize,
}

/// A velocity component at the start of a step from the Press history:
/// the last displacement over the last step plus the kick of the second
/// half of that step, `dX / dt_prev + a dt_prev / 2`.
#[inline]
pub fn velocity_now(displacement: f64, a: f64, dt_prev: f64) -> f64 {
    displacement / dt_prev + a * (0.5 * dt_prev)
}

/// Closes the steps that end now: each particle of `range` for which
/// `last_step(i)` gives the length of the step it just finished gets its
/// velocity at this time, `v_n = dX / dt + a_n dt / 2` ([`velocity_now`],
/// with its new acceleration `a_n`); the others keep theirs.
///
/// Between kicks a particle carries the prediction `v + a t` of the
/// acceleration at its step's start, first order in its step: conserved
/// sums over predicted velocities mix that error with the integrator's
/// (Sedov 20^3, block steps at Courant 0.4: an energy drift of 2.2e-3
/// over predicted velocities, 6.6e-4 over closed ones). The next kick
/// recomputes the same `v_n` from `dX`, so closing a step changes no
/// trajectory.
///
/// ```
/// use sph_core::integrate::close_steps;
/// use sph_core::{FieldSet, Particles};
/// let mut p = Particles::new(2, FieldSet::default());
/// p.dx[0] = 0.2; // moved 0.2 in a step of 0.1 ...
/// p.ax[0] = 4.0; // ... and now accelerates
/// p.vx[1] = 7.0;
/// close_steps(&mut p, 0..2, |i| (i == 0).then_some(0.1));
/// assert!((p.vx[0] - (2.0 + 0.2)).abs() < 1e-15);
/// assert_eq!(p.vx[1], 7.0); // inside its step: the prediction stays
/// ```
pub fn close_steps(
    p: &mut Particles,
    range: Range<usize>,
    last_step: impl Fn(usize) -> Option<f64> + Sync,
) {
    let (ax, ay, az) = (&p.ax, &p.ay, &p.az);
    let (dx, dy, dz) = (&p.dx, &p.dy, &p.dz);
    let o = range.start;
    (
        p.vx[range.clone()].par_iter_mut(),
        p.vy[range.clone()].par_iter_mut(),
        p.vz[range].par_iter_mut(),
    )
        .into_par_iter()
        .enumerate()
        .for_each(|(k, (vx, vy, vz))| {
            let i = o + k;
            if let Some(dt) = last_step(i) {
                *vx = velocity_now(dx[i], ax[i], dt);
                *vy = velocity_now(dy[i], ay[i], dt);
                *vz = velocity_now(dz[i], az[i], dt);
            }
        });
}

/// Stores the new position `newp`, wrapped into `bbox`, in `pos`; an
/// error names the particle when a coordinate or its velocity `vel` is not
/// finite.
#[inline]
pub(crate) fn place(
    pos: [&mut f64; 3],
    newp: [f64; 3],
    vel: [f64; 3],
    bbox: &BoundingBox,
    step: u64,
    id: u64,
) -> Result<(), CoreError> {
    let wrapped = bbox.wrap(newp);
    for (k, p) in pos.into_iter().enumerate() {
        if !wrapped[k].is_finite() || !vel[k].is_finite() {
            return Err(CoreError::NonFinite {
                step,
                id,
                field: ["x", "y", "z"][k],
                value: if wrapped[k].is_finite() {
                    vel[k]
                } else {
                    wrapped[k]
                },
            });
        }
        *p = wrapped[k];
    }
    Ok(())
}

/// Advances the particles of `range` by `dt` (the previous step was `dt_prev`), wraps
/// positions into periodic boxes and updates h (when `h_update` is given)
/// from the neighbour counts `p.nc`. With `energy_guard`, a negative
/// internal energy falls back to first order and then is an error (set it
/// when pressure depends on u).
pub fn integrate(
    p: &mut Particles,
    range: Range<usize>,
    bbox: &BoundingBox,
    dt: f64,
    dt_prev: f64,
    h_update: Option<HUpdate>,
    energy_guard: bool,
    step: u64,
) -> Result<IntegrateReport, CoreError> {
    let (ax, ay, az, du, nc, id) = (&p.ax, &p.ay, &p.az, &p.du, &p.nc, &p.id);
    let result: Result<usize, CoreError> = (
        p.x[range.clone()].par_iter_mut(),
        p.y[range.clone()].par_iter_mut(),
        p.z[range.clone()].par_iter_mut(),
        p.vx[range.clone()].par_iter_mut(),
        p.vy[range.clone()].par_iter_mut(),
        p.vz[range.clone()].par_iter_mut(),
        p.dx[range.clone()].par_iter_mut(),
        p.dy[range.clone()].par_iter_mut(),
        p.dz[range.clone()].par_iter_mut(),
        p.u[range.clone()].par_iter_mut(),
        p.du_prev[range.clone()].par_iter_mut(),
        p.h[range.clone()].par_iter_mut(),
    )
        .into_par_iter()
        .enumerate()
        .map(|(k, (x, y, z, vx, vy, vz, dx, dy, dz, u, du_prev, h))| {
            let i = range.start + k;
            let a = [ax[i], ay[i], az[i]];
            let pos = [x, y, z];
            let vel = [vx, vy, vz];
            let dpos = [dx, dy, dz];
            let mut newp = [0.0; 3];
            for k in 0..3 {
                let v_n = velocity_now(*dpos[k], a[k], dt_prev);
                let step_k = (v_n + 0.5 * a[k] * dt) * dt;
                newp[k] = *pos[k] + step_k;
                *dpos[k] = step_k;
                *vel[k] = v_n + a[k] * dt;
            }
            place(pos, newp, [*vel[0], *vel[1], *vel[2]], bbox, step, id[i])?;
            // Adams-Bashforth 2; first order if that would go negative.
            let d = du[i];
            let mut fallback = 0;
            let mut un = *u + d * dt + 0.5 * (d - *du_prev) / dt_prev * dt * dt;
            if energy_guard && (un.is_nan() || un < 0.0) {
                fallback = 1;
                un = *u + d * dt;
                if un.is_nan() || un < 0.0 {
                    return Err(CoreError::NegativeEnergy {
                        step,
                        id: id[i],
                        u: un,
                        du: d,
                        dt,
                    });
                }
            }
            *u = un;
            *du_prev = d;
            if let Some(hu) = h_update {
                *h *= hu.factor(nc[i]);
            }
            Ok(fallback)
        })
        .try_reduce(|| 0, |a, b| Ok(a + b));
    Ok(IntegrateReport {
        energy_fallbacks: result?,
    })
}
