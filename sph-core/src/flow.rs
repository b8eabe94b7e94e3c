//! The per-particle state the pair stages read: what the momentum and
//! energy equations read ([`HydroState`]), what the switch stages read
//! ([`FlowState`]), and both cut to one length for the pair loop
//! (`Flow`). Its own module so that the stages that read it do not
//! depend on each other.

use crate::density::Positions;
use crate::pair_loop::PairLoop;
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};

/// The per-particle state the momentum and energy equations read.
#[derive(Debug, Clone, Copy)]
pub struct HydroState<'a> {
    /// Positions, smoothing lengths and masses.
    pub pos: Positions<'a>,
    /// Velocity x.
    pub vx: &'a [f64],
    /// Velocity y.
    pub vy: &'a [f64],
    /// Velocity z.
    pub vz: &'a [f64],
    /// Density.
    pub rho: &'a [f64],
    /// Pressure.
    pub p: &'a [f64],
    /// Sound speed.
    pub c: &'a [f64],
    /// grad-h factor (empty: 1).
    pub omega: &'a [f64],
    /// Inverse IAD matrices (used with [`Gradients::Iad`](crate::pair_loop::Gradients::Iad)).
    pub iad: [&'a [f64]; 6],
}

/// The per-particle state the switch stages read.
#[derive(Debug, Clone, Copy)]
pub struct FlowState<'a> {
    /// Positions, smoothing lengths and masses.
    pub pos: Positions<'a>,
    /// Velocity x.
    pub vx: &'a [f64],
    /// Velocity y.
    pub vy: &'a [f64],
    /// Velocity z.
    pub vz: &'a [f64],
    /// Density (volumes `m / rho`).
    pub rho: &'a [f64],
    /// Sound speed (read by the second pass only).
    pub c: &'a [f64],
    /// Inverse IAD matrices `(xx, xy, xz, yy, yz, zz)` (read with
    /// [`Gradients::Iad`](crate::pair_loop::Gradients::Iad) only).
    pub iad: [&'a [f64]; 6],
}

impl<'a> From<HydroState<'a>> for FlowState<'a> {
    fn from(s: HydroState<'a>) -> Self {
        Self {
            pos: s.pos,
            vx: s.vx,
            vy: s.vy,
            vz: s.vz,
            rho: s.rho,
            c: s.c,
            iad: s.iad,
        }
    }
}

/// What the pair stages read of every particle, cut to one length (so
/// one bounds check per run of neighbours covers every load).
pub(crate) struct Flow<'a, K> {
    pub(crate) kernel: &'a K,
    pub(crate) norm: f64,
    pub(crate) support: f64,
    pub(crate) h: &'a [f64],
    pub(crate) m: &'a [f64],
    pub(crate) v: [&'a [f64]; 3],
    pub(crate) rho: &'a [f64],
    pub(crate) c: &'a [f64],
    pub(crate) iad: [&'a [f64]; 6],
}

impl<'a, K: Kernel> Flow<'a, K> {
    /// `flow` with its IAD matrices when `iad`.
    pub(crate) fn new(kernel: &'a K, flow: &FlowState<'a>, iad: bool) -> Self {
        let n = flow.pos.x.len();
        let cut = |a: &'a [f64]| &a[..n];
        Self {
            kernel,
            norm: kernel.norm(),
            support: kernel.support(),
            h: cut(flow.pos.h),
            m: cut(flow.pos.m),
            v: [cut(flow.vx), cut(flow.vy), cut(flow.vz)],
            rho: cut(flow.rho),
            c: if flow.c.is_empty() {
                flow.c
            } else {
                cut(flow.c)
            },
            iad: if iad { flow.iad.map(cut) } else { [&[]; 6] },
        }
    }

    /// The pair-loop driver over `flow`'s positions.
    pub(crate) fn driver(
        bbox: &BoundingBox,
        kernel: &K,
        flow: &FlowState<'a>,
        nl: &'a CompactNeighborList,
    ) -> PairLoop<'a> {
        let pos = flow.pos;
        PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
            .expect("AV switches: positions")
    }
}
