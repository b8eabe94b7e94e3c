//! The stirring stage of a driven run ([`HydroConfig::stirring`](super::HydroConfig::stirring)):
//! the OU update, the stirring acceleration with its net impulse removed,
//! and the terms of its work.

use super::Hydro;
use crate::conserved::exact_sums;
use crate::integrate::velocity_now;
use crate::stirring::Stirring;
use crate::{CoreError, Particles};
use rayon::prelude::*;
use sph_comm::{Communicator, ExactSum};
use sph_kernels::Kernel;
use sph_tree::BoundingBox;
use std::ops::Range;

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// Advances the driving by the last step (at the first step, the first
    /// `dt0`; the state is built then, from the box) and adds the stirring
    /// acceleration to the owned particles' `a`, less its mass-weighted
    /// mean, so that it injects no net momentum. Every rank draws the same
    /// numbers in the same order and the mean is an exact sum: the result
    /// does not depend on the rank or thread count.
    pub(super) fn stir(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
    ) -> Result<(), CoreError> {
        let advanced =
            advance_driving(&mut self.stirring, self.config.stirring, bbox, self.dt_prev);
        let Some(stirring) = advanced? else {
            return Ok(());
        };
        let n = owned.len();
        let [sx, sy, sz] = zeroed(&mut self.buf.stir, n);
        let r = owned.clone();
        stirring.accelerate(&p.x[r.clone()], &p.y[r.clone()], &p.z[r], sx, sy, sz);

        let m = &p.m[owned.clone()];
        let sums = exact_sums(n, |i, s: &mut [ExactSum; 4]| {
            s[0].add(m[i]);
            s[1].add(m[i] * sx[i]);
            s[2].add(m[i] * sy[i]);
            s[3].add(m[i] * sz[i]);
        });
        let mean = global_mean(sums, self.domain.comm());
        let (ax, ay, az) = (
            &mut p.ax[owned.clone()],
            &mut p.ay[owned.clone()],
            &mut p.az[owned],
        );
        for (s, a, mean) in [(sx, ax, mean[0]), (sy, ay, mean[1]), (sz, az, mean[2])] {
            s.par_iter_mut().zip(a.par_iter_mut()).for_each(|(s, a)| {
                *s -= mean;
                *a += *s;
            });
        }
        Ok(())
    }

    /// This rank's exact partial sums `[sum m a_s . v_n, sum m a_s . a]` of
    /// the owned particles (`a` the total acceleration, `v_n` the velocity
    /// at the step's start: [`velocity_now`]); the step's work is
    /// `S1 dt + S2 dt^2 / 2`. Zero sums without stirring.
    pub(super) fn stir_work_sums(&self, p: &Particles, owned: Range<usize>) -> [ExactSum; 2] {
        if self.config.stirring.is_none() {
            return Default::default();
        }
        let [sx, sy, sz] = &self.buf.stir;
        let dt_prev = self.dt_prev;
        let o = owned.start;
        let [s1, s2] = exact_sums(owned.len(), |k, s: &mut [ExactSum; 2]| {
            let i = o + k;
            let a_s = [sx[k], sy[k], sz[k]];
            let a = [p.ax[i], p.ay[i], p.az[i]];
            let d = [p.dx[i], p.dy[i], p.dz[i]];
            let (mut sv, mut sa) = (0.0, 0.0);
            for c in 0..3 {
                sv += a_s[c] * velocity_now(d[c], a[c], dt_prev);
                sa += a_s[c] * a[c];
            }
            s[0].add(p.m[i] * sv);
            s[1].add(p.m[i] * sa);
        });
        [s1, s2]
    }

    /// [`Hydro::stir`] under block time steps: advances the driving by the
    /// last sub-step and gives the active owned particles (`active[k]` for
    /// the `k`-th owned one) the stirring acceleration at their positions,
    /// kept in `p.stir_a` over their step. One constant is taken off the
    /// new accelerations so that the kept accelerations of all particles
    /// (the inactive ones': those of their step's start) have a zero
    /// mass-weighted sum: the driving's net force stays zero while
    /// particles drift (kicks over steps of different lengths still
    /// leave a small net impulse, as block steps do for the pair forces).
    /// Exact sums: independent of rank and thread counts.
    pub(super) fn stir_active(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        active: &[bool],
    ) -> Result<(), CoreError> {
        let advanced =
            advance_driving(&mut self.stirring, self.config.stirring, bbox, self.dt_prev);
        let Some(stirring) = advanced? else {
            return Ok(());
        };
        let o = owned.start;
        let [px, py, pz] = &mut self.buf.stir_at;
        for (at, pos) in [(&mut *px, &p.x), (&mut *py, &p.y), (&mut *pz, &p.z)] {
            at.clear();
            at.extend(owned.clone().filter(|i| active[i - o]).map(|i| pos[i]));
        }
        let [sx, sy, sz] = zeroed(&mut self.buf.stir, px.len());
        stirring.accelerate(px, py, pz, sx, sy, sz);

        // Scatter the new accelerations into the kept ones, then the sums
        // over all owned particles: the active ones' mass, and every
        // particle's kept mass-weighted acceleration.
        for (k, i) in owned.clone().filter(|i| active[i - o]).enumerate() {
            p.stir_a[0][i] = sx[k];
            p.stir_a[1][i] = sy[k];
            p.stir_a[2][i] = sz[k];
        }
        let (m, kept) = (&p.m, &p.stir_a);
        let sums = exact_sums(owned.len(), |k, s: &mut [ExactSum; 4]| {
            let i = o + k;
            if active[k] {
                s[0].add(m[i]);
            }
            for c in 0..3 {
                s[c + 1].add(m[i] * kept[c][i]);
            }
        });
        let shift = global_mean(sums, self.domain.comm());
        let a = [&mut p.ax, &mut p.ay, &mut p.az];
        for ((kept, a), shift) in p.stir_a.iter_mut().zip(a).zip(shift) {
            kept[owned.clone()]
                .par_iter_mut()
                .zip(a[owned.clone()].par_iter_mut())
                .zip(active.par_iter())
                .filter(|(_, &on)| on)
                .for_each(|((s, a), _)| {
                    *s -= shift;
                    *a += *s;
                });
        }
        Ok(())
    }

    /// The stirring's work over a drift under block time steps, summed
    /// exactly over all ranks: `sum m a_s . dx` with `a_s` the kept
    /// stirring acceleration and `dx` the drift's position change (the
    /// particle's step displacement times `share(i)`, its part of the
    /// step). Zero, and no collective, without stirring.
    pub(super) fn stir_drift_work(
        &self,
        p: &Particles,
        owned: Range<usize>,
        share: impl Fn(usize) -> f64 + Sync,
    ) -> f64 {
        if self.config.stirring.is_none() {
            return 0.0;
        }
        let o = owned.start;
        let [mut w] = exact_sums(owned.len(), |k, s: &mut [ExactSum; 1]| {
            let i = o + k;
            let f = share(i);
            let d = [p.dx[i], p.dy[i], p.dz[i]];
            let w: f64 = (0..3).map(|c| p.stir_a[c][i] * (d[c] * f)).sum();
            s[0].add(p.m[i] * w);
        });
        w.all_reduce(self.domain.comm());
        w.value()
    }

    /// The driving state (phases and generator) for checkpoints, once a
    /// stirred run has taken a step.
    pub fn stirring(&self) -> Option<&Stirring> {
        self.stirring.as_ref()
    }

    /// Continues a stirred run from a checkpoint's driving state (see
    /// [`Stirring::restore`]), in the run's box.
    ///
    /// # Errors
    /// A run without stirring, a box the stirring refuses, or a state of
    /// the wrong size.
    pub fn restore_stirring(
        &mut self,
        bbox: &BoundingBox,
        phases: &[f64],
        rng_state: &[f64],
    ) -> Result<(), CoreError> {
        let Some(params) = self.config.stirring else {
            return Err(CoreError::Invalid(
                "a stirring state was given to a run without stirring".into(),
            ));
        };
        let mut s = Stirring::new(params, bbox)?;
        s.restore(phases, rng_state)?;
        self.stirring = Some(s);
        Ok(())
    }
}

/// The driving in `slot` (built from `params` and the box at the first
/// call) advanced by `dt`: `None` without stirring.
fn advance_driving<'a>(
    slot: &'a mut Option<Stirring>,
    params: Option<crate::stirring::StirParams>,
    bbox: &BoundingBox,
    dt: f64,
) -> Result<Option<&'a Stirring>, CoreError> {
    let Some(params) = params else {
        return Ok(None);
    };
    let stirring = match slot {
        Some(s) => s,
        slot => slot.insert(Stirring::new(params, bbox)?),
    };
    stirring.advance(dt);
    Ok(Some(stirring))
}

/// `[sum m a_x, sum m a_y, sum m a_z] / sum m` over all ranks from this
/// rank's exact sums `[m, m a_x, m a_y, m a_z]` (zero for zero mass).
fn global_mean<C: Communicator>(mut sums: [ExactSum; 4], comm: &C) -> [f64; 3] {
    ExactSum::all_reduce_many(&mut sums, comm);
    let mass = sums[0].value();
    [1, 2, 3].map(|k| {
        if mass > 0.0 {
            sums[k].value() / mass
        } else {
            0.0
        }
    })
}

/// The three acceleration buffers, each `n` zeros.
fn zeroed(bufs: &mut [Vec<f64>; 3], n: usize) -> &mut [Vec<f64>; 3] {
    for s in bufs.iter_mut() {
        s.clear();
        s.resize(n, 0.0);
    }
    bufs
}
