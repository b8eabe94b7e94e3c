//! The artificial conduction under block time steps, as impulses
//! (`docs/block-timesteps.md`, "Conduction as impulses").
//!
//! A pair's conduction is antisymmetric, so one global step exchanges it
//! exactly; as a rate held over each particle's own step it is not (the
//! particle with the long step keeps gaining at the rate of its last
//! update while its hot neighbour, re-evaluated every short step, loses
//! less). Here each pair's flux is integrated over the shorter of the two
//! steps and given to both partners at the kick of the one whose step
//! starts now ([`ConductionImpulses`]): the particles that start a step
//! are the targets of one pass, their partners inside a longer step the
//! targets of a second (their lists come from a search over them alone).
//! The momentum pass leaves the conduction out of `du` on the time line,
//! so the Adams-Bashforth correction and the drift of `u` carry the
//! hydrodynamics only; the conduction is first order in time.

use super::Hydro;
use crate::conduction::{ConductionImpulses, Conductivity};
use crate::pair_loop::PairLoop;
use crate::timeline::TimeLine;
use crate::{CoreError, Particles};
use sph_comm::Communicator;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList, NeighborSearch, GROUP_LANES};
use std::ops::Range;
use std::sync::atomic::{AtomicU8, Ordering};

/// Work arrays of the impulses (allocated only with conduction on the
/// time line).
#[derive(Debug, Default)]
pub(super) struct ImpulseBuffers {
    /// Per local particle: the step it starts now or is inside.
    step: Vec<f64>,
    /// Per local particle: 1 where its step starts now, else 0.
    starts: Vec<f64>,
    /// Per local particle: 0 where a particle starting its step meets it
    /// inside its own.
    met: Vec<AtomicU8>,
    /// Per owned particle: a receiver (inside its step, met).
    receivers: Vec<bool>,
    /// The receivers' neighbour lists.
    list: CompactNeighborList,
    /// Per owned particle: its impulse of `u`.
    du: Vec<f64>,
}

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// The impulses of `u` of this sub-step into `self.impulses.du`, per
    /// owned particle, or nothing without conduction, once the new bins
    /// are chosen ([`BlockState::bin_from_now`](super::block::BlockState::bin_from_now)). Collective.
    pub(super) fn conduction_impulses(
        &mut self,
        p: &Particles,
        bbox: &BoundingBox,
        line: &TimeLine,
        owned: Range<usize>,
    ) -> Result<(), CoreError> {
        let s = self.config.scheme;
        let Some(alpha_u) = s.conductivity else {
            return Ok(());
        };
        let n = p.len();
        let o = owned.start;
        let b = &mut self.impulses;
        b.step.clear();
        b.step.resize(n, 0.0);
        b.starts.clear();
        b.starts.resize(n, 0.0);
        for k in 0..owned.len() {
            let (bin, starts) = self.block.bin_from_now(p, o + k, k);
            b.step[o + k] = line.dt(bin);
            b.starts[o + k] = f64::from(u8::from(starts));
        }
        self.domain
            .exchange(&mut [b.step.as_mut_slice(), b.starts.as_mut_slice()])?;
        b.met.clear();
        b.met.resize_with(n, || AtomicU8::new(1));
        b.du.clear();
        b.du.resize(owned.len(), 0.0);
        let stage = |receivers| ConductionImpulses {
            kernel: &self.kernel,
            h: &p.h,
            m: &p.m,
            rho: &p.rho,
            c: Conductivity {
                alpha_u,
                p: &p.p,
                u: &p.u,
                contrast: s.conduction_contrast,
            },
            step: &b.step,
            starts: &b.starts,
            receivers,
        };
        let support = self.kernel.support();
        let xyz = [p.x.as_slice(), &p.y, &p.z];
        PairLoop::new(bbox, support, xyz, &p.h, &self.list)?
            .run(&stage(Some(&b.met)), [&mut b.du[..]]);
        if self.domain.comm().size() > 1 {
            let mut met: Vec<u8> = b.met.iter().map(|m| m.load(Ordering::Relaxed)).collect();
            self.domain.exchange_reverse_min(&mut met)?;
            for (m, v) in b.met.iter().zip(met) {
                m.store(v, Ordering::Relaxed);
            }
        }
        b.receivers.clear();
        b.receivers.extend(
            owned
                .clone()
                .map(|i| b.starts[i] == 0.0 && b.met[i].load(Ordering::Relaxed) == 0),
        );
        if !b.receivers.contains(&true) {
            return Ok(());
        }
        let groups: Vec<bool> = b
            .receivers
            .chunks(GROUP_LANES)
            .map(|g| g.contains(&true))
            .collect();
        let search = NeighborSearch {
            symmetric: true,
            grouped: true,
            ..NeighborSearch::default()
        };
        search.find_compact_groups(
            &self.tree,
            bbox,
            &p.x,
            &p.y,
            &p.z,
            &p.h,
            owned.clone(),
            &groups,
            &mut b.list,
        )?;
        b.list.set_active_targets(&b.receivers);
        PairLoop::new(bbox, support, xyz, &p.h, &b.list)?.run(&stage(None), [&mut b.du[..]]);
        Ok(())
    }

    /// Adds the impulses to the owned particles' `u`; an impulse that
    /// would leave `u` negative (a receiver losing to many partners at
    /// once) takes half of it instead. Returns how many did.
    pub(super) fn apply_conduction_impulses(
        &mut self,
        p: &mut Particles,
        owned: Range<usize>,
    ) -> usize {
        if self.config.scheme.conductivity.is_none() {
            return 0;
        }
        let mut limited = 0;
        for (u, &du) in p.u[owned].iter_mut().zip(&self.impulses.du) {
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
