//! The artificial conduction under block time steps, as impulses
//! (`docs/block-timesteps.md`, "Conduction as impulses";
//! [`ImpulseWeights`](crate::conduction::ImpulseWeights)).
//!
//! A pair's conduction is antisymmetric, so one global step exchanges it
//! exactly; as a rate held over each particle's own step it is not (the
//! particle with the long step keeps its last rate while its hot
//! neighbour, re-evaluated every short step, loses less). Here the
//! momentum pass gives each pair's term times the time since the pair's
//! last exchange to both partners at once: to the particle starting a
//! step in its impulse, to a partner inside its step in fixed point
//! (brought to its owner rank by a reverse exchange). `du` then carries
//! the hydrodynamics only (the Adams-Bashforth correction and the drift
//! of `u`); the impulses go into `u` at the kick.

use super::Hydro;
use crate::timeline::{step_begin, Ticks, TimeLine};
use crate::{CoreError, Particles};
use sph_comm::{Communicator, ReduceOp};
use sph_kernels::Kernel;
use std::ops::Range;
use std::sync::atomic::{AtomicI64, Ordering};

/// The fixed point of the partners' impulses: `2^-QUANTUM_BITS` of the
/// largest `u`. An impulse is at most a few times the `u` of the hotter
/// partner, far inside the `2^(63 - QUANTUM_BITS)` the integers hold; its
/// rounding is 1.4e-17 of the largest `u` per pair.
const QUANTUM_BITS: i32 = 56;

/// Work arrays of the impulses (filled only with conduction on the time
/// line).
#[derive(Debug, Default)]
pub(super) struct ImpulseBuffers {
    /// Per local particle: the time since its last kick.
    pub(super) since: Vec<f64>,
    /// Per local particle: whether its step starts now.
    pub(super) starts: Vec<bool>,
    /// Per local particle: the impulse received inside its step, in
    /// units of `1 / inv_quantum`.
    pub(super) gains: Vec<AtomicI64>,
    pub(super) inv_quantum: f64,
    /// Per local particle: its impulse of `u` (owned particles).
    pub(super) du: Vec<f64>,
    /// `since` and `starts` as numbers, for the halo exchange.
    exchanged: [Vec<f64>; 2],
}

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// The impulses' inputs for the momentum pass of the sub-step at tick
    /// `ti`: each owned particle's time since its last kick and whether
    /// it starts a step (halos get their owners'), the fixed point, zeroed
    /// sums. Nothing without conduction. Collective.
    pub(super) fn prepare_impulses(
        &mut self,
        p: &Particles,
        line: &TimeLine,
        owned: Range<usize>,
        ti: Ticks,
    ) -> Result<(), CoreError> {
        if self.config.scheme.conductivity.is_none() {
            return Ok(());
        }
        let n = p.len();
        let b = &mut self.impulses;
        let [since, starts] = &mut b.exchanged;
        for v in [&mut *since, &mut *starts] {
            v.clear();
            v.resize(n, 0.0);
        }
        let now = line.time(ti);
        let elapsed = self.block.elapsed();
        for (k, i) in owned.clone().enumerate() {
            if self.block.is_active(k) {
                // The step that just ended (0 at the first sub-step).
                since[i] = elapsed[i];
                starts[i] = 1.0;
            } else {
                let bin = super::block::bin_of(p.bin[i]);
                since[i] = now - line.time(step_begin(ti, bin));
            }
        }
        self.domain
            .exchange(&mut [since.as_mut_slice(), starts.as_mut_slice()])?;
        b.since.clear();
        b.since.extend_from_slice(since);
        b.starts.clear();
        b.starts.extend(starts.iter().map(|&s| s != 0.0));
        let u_max = owned.clone().map(|i| p.u[i]).fold(0.0, f64::max);
        let u_max = self.domain.comm().all_reduce_scalar(u_max, ReduceOp::Max);
        // Without heat nothing flows: zero weights the partners' sides.
        b.inv_quantum = if u_max > 0.0 && u_max.is_finite() {
            2f64.powi(QUANTUM_BITS) / u_max
        } else {
            0.0
        };
        b.gains.clear();
        b.gains.resize_with(n, || AtomicI64::new(0));
        b.du.clear();
        b.du.resize(n, 0.0);
        Ok(())
    }

    /// After the momentum pass: the partners' fixed-point impulses summed
    /// on their owners and added to the owned particles' impulses.
    /// Collective.
    pub(super) fn gather_impulses(&mut self, owned: Range<usize>) -> Result<(), CoreError> {
        if self.config.scheme.conductivity.is_none() {
            return Ok(());
        }
        let b = &mut self.impulses;
        if self.domain.comm().size() > 1 {
            let mut gains: Vec<i64> = b.gains.iter().map(|g| g.load(Ordering::Relaxed)).collect();
            self.domain
                .exchange_reverse_with(&mut gains, |own, v| *own = own.wrapping_add(v))?;
            for (g, v) in b.gains.iter().zip(gains) {
                g.store(v, Ordering::Relaxed);
            }
        }
        if b.inv_quantum > 0.0 {
            let quantum = 1.0 / b.inv_quantum;
            for i in owned {
                let gain = b.gains[i].load(Ordering::Relaxed);
                if gain != 0 {
                    b.du[i] += gain as f64 * quantum;
                }
            }
        }
        Ok(())
    }

    /// Adds the impulses to the owned particles' `u`; an impulse that
    /// would leave `u` negative (a partner losing to many others at once)
    /// takes half of it instead. Returns how many did.
    pub(super) fn apply_impulses(&mut self, p: &mut Particles, owned: Range<usize>) -> usize {
        if self.config.scheme.conductivity.is_none() {
            return 0;
        }
        let mut limited = 0;
        for i in owned {
            let (u, du) = (&mut p.u[i], self.impulses.du[i]);
            let new = *u + du;
            if new >= 0.0 {
                *u = new;
            } else {
                *u *= 0.5;
                limited += 1;
            }
        }
        limited
    }
}
