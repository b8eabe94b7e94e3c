//! Artificial conductivity of internal energy (Price 2008): a diffusion of
//! `u` across pressure jumps that smooths the spurious entropy spikes
//! viscosity leaves at shocks and walls ("wall heating" in the Noh test).
//!
//! ```text
//! du_i/dt += sum_j m_j alpha_u v_u (u_i - u_j) / rho_ij * (W'(r, h_i) + W'(r, h_j)) / 2
//! v_u = sqrt(|P_i - P_j| / rho_ij),   rho_ij = (rho_i + rho_j) / 2,
//! ```
//!
//! with `W'(r, h) = dW/dr <= 0`, so heat flows from hot to cold. The pair
//! term is antisymmetric: `sum_i m_i du_i/dt` is unchanged (total energy
//! conserved to round-off). The solver adds it inside the momentum pass
//! ([`Conductivity`] in [`MomentumScheme`](crate::momentum::MomentumScheme):
//! the pairs and their partners' data are already at hand there);
//! [`conduction`] is the same sum as a pass of its own.

use crate::density::Positions;
use crate::pair_loop::{F64s, Group, PairLoop, PairStage};
use crate::Choice;
use serde::{Deserialize, Serialize};
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList};
use std::sync::atomic::{AtomicI64, Ordering};

/// Adds the conductive heating rate to `du` for every target of `nl`
/// (neighbours in ascending order: independent of the thread count).
/// `rho`, `p` and `u` must cover every particle the lists reach.
///
/// ```
/// use sph_core::conduction::conduction;
/// use sph_core::density::Positions;
/// use sph_kernels::{CubicSpline, Kernel};
/// use sph_tree::{compute_keys, Boundary, BoundingBox, CompactNeighborList, Curve};
/// use sph_tree::{NeighborSearch, Octree};
///
/// // Two particles 0.5 apart, the left one hotter and at higher pressure.
/// let (x, y, z) = (vec![0.25, 0.75], vec![0.5; 2], vec![0.5; 2]);
/// let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Open).unwrap();
/// let mut keys = Vec::new();
/// compute_keys(&bbox, Curve::Hilbert, &x, &y, &z, &mut keys);
/// let (x, y, z, keys) = if keys[0] <= keys[1] {
///     (x, y, z, keys)
/// } else {
///     (vec![0.75, 0.25], y, z, vec![keys[1], keys[0]])
/// };
/// let tree = Octree::build(&keys, &x, &y, &z, 4).unwrap();
/// let h = vec![0.4; 2];
/// let mut list = CompactNeighborList::new();
/// NeighborSearch::default().find_compact(&tree, &bbox, &x, &y, &z, &h, 0..2, &mut list).unwrap();
/// let m = vec![1.0; 2];
/// let pos = Positions { x: &x, y: &y, z: &z, h: &h, m: &m };
/// let hot = if x[0] < 0.5 { 0 } else { 1 };
/// let mut u = vec![1.0; 2];
/// let mut p = vec![1.0; 2];
/// u[hot] = 2.0;
/// p[hot] = 2.0;
/// let mut du = vec![0.0; 2];
/// conduction(&CubicSpline, &bbox, pos, &[1.0; 2], &p, &u, 1.0, &list, &mut du);
/// assert!(du[hot] < 0.0 && du[1 - hot] > 0.0);
/// assert!((du[0] + du[1]).abs() < 1e-15); // equal masses: energy kept
/// ```
///
/// # Panics
/// If the arrays differ in length or do not cover the lists.
#[allow(clippy::too_many_arguments)]
pub fn conduction<K: Kernel>(
    kernel: &K,
    bbox: &BoundingBox,
    pos: Positions<'_>,
    rho: &[f64],
    p: &[f64],
    u: &[f64],
    alpha_u: f64,
    nl: &CompactNeighborList,
    du: &mut [f64],
) {
    let driver = PairLoop::new(bbox, kernel.support(), [pos.x, pos.y, pos.z], pos.h, nl)
        .expect("conduction: positions");
    let stage = Conduction {
        kernel,
        norm: kernel.norm(),
        h: pos.h,
        m: pos.m,
        rho,
        c: Conductivity {
            alpha_u,
            p,
            u,
            contrast: Contrast::Off,
            impulses: None,
        },
    };
    driver.run(&stage, [&mut du[nl.targets()]]);
}

/// What weights each pair's conduction term (`--conduction-contrast`).
///
/// The weight is a contrast in `[0, 1]`: the flux then goes as the square
/// of a small jump, so heat crosses fronts at full strength while
/// neighbours that differ little exchange less. Antisymmetric whatever
/// the weight: energy is conserved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Contrast {
    /// Price's term as it is.
    #[default]
    Off,
    /// Weighted by the pair's contrast of internal energy,
    /// `|u_i - u_j| / max(u_i, u_j)`: Sod's contact (u differing by 2x)
    /// exchanges less than with Price's term, but so does a cold
    /// collapse's shocked core, whose u differs little between neighbours
    /// (`docs/schemes.md`, 2026-12-06 and 2026-12-07).
    Energy,
    /// Weighted by the pair's contrast of pressure,
    /// `min(|P_i - P_j| / max(|P_i|, |P_j|), 1)`: contacts in pressure
    /// equilibrium exchange nearly nothing (the signal velocity
    /// `sqrt(|P_i - P_j| / rho_ij)` already vanishes there), while the
    /// pressure noise of a shocked core and every shock conduct. So does
    /// not the hot, nearly isobaric interior of a blast: Sedov's L1 P at
    /// 50^3 is 0.1865 with it against 0.1773 with [`Larger`](Self::Larger)
    /// (`gas` otherwise).
    Pressure,
    /// The larger of the two contrasts: heat crosses a jump of pressure
    /// (a shocked core's noise, where neighbours' `u` differ little) and a
    /// large jump of `u` (a blast's hot interior), while a contact's
    /// modest jump of `u` at one pressure exchanges as with
    /// [`Energy`](Self::Energy) (`docs/schemes.md`, 2026-12-07, evening).
    /// The pressure noise of a subsonic shear layer conducts too:
    /// Kelvin-Helmholtz's M(1.5) at 64^2 x 8 is 0.1053 with it against
    /// 0.1137 with [`Energy`](Self::Energy) (2026-12-07, night).
    Larger,
}

/// `--conduction-contrast` and the `conduction-contrast` key.
impl Choice for Contrast {
    const ALL: &'static [Self] = &[
        Contrast::Off,
        Contrast::Energy,
        Contrast::Pressure,
        Contrast::Larger,
    ];

    fn name(&self) -> &'static str {
        match self {
            Contrast::Off => "off",
            Contrast::Energy => "energy",
            Contrast::Pressure => "pressure",
            Contrast::Larger => "larger",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            Contrast::Off => "Price's conduction as it is",
            Contrast::Energy => {
                "Each pair's term times |u_i - u_j| / max(u_i, u_j), its contrast of internal \
                 energy"
            }
            Contrast::Pressure => {
                "Each pair's term times min(|P_i - P_j| / max(|P_i|, |P_j|), 1), its contrast \
                 of pressure"
            }
            Contrast::Larger => {
                "Each pair's term times the larger of its contrasts of internal energy and of \
                 pressure (`gas`'s)"
            }
        }
    }
}

/// The conductivity of a momentum pass: `alpha_u` and the pressure and
/// internal energy of every particle the lists reach.
#[derive(Debug, Clone, Copy)]
pub struct Conductivity<'a> {
    /// `alpha_u`.
    pub alpha_u: f64,
    /// Pressure.
    pub p: &'a [f64],
    /// Internal energy per mass.
    pub u: &'a [f64],
    /// What weights each pair's term ([`Contrast`]).
    pub contrast: Contrast,
    /// Under block time steps, the pair terms as impulses
    /// ([`ImpulseWeights`]); `None`: a rate added to `du/dt`.
    pub impulses: Option<ImpulseWeights<'a>>,
}

/// The conduction under block time steps as impulses
/// (`docs/block-timesteps.md`, "Conduction as impulses"). A pair's term as
/// a rate held over each particle's own step is not conserved (the
/// particle with the longer step keeps its last rate while its partner
/// is re-evaluated); as impulses each pair exchanges, whenever one of
/// the two starts a step, its term times the time since the pair's last
/// exchange, `min(since_i, since_j)` (the later of the two partners' last
/// kicks), on both sides at once: the target (starting a step) in its
/// sum, a partner inside its step in its [`gains`](Self::gains), in fixed
/// point (integer sums do not depend on the order of the adds: runs stay
/// independent of thread and rank counts). The exchanges tile time and
/// each is one antisymmetric term times one interval: energy is
/// conserved to round-off whatever the steps.
#[derive(Debug, Clone, Copy)]
pub struct ImpulseWeights<'a> {
    /// Per local particle: the time since its last kick (the step it
    /// just ended where it starts one now, else the time since its step
    /// began).
    pub since: &'a [f64],
    /// Per local particle: whether its step starts now.
    pub starts: &'a [bool],
    /// Per local particle: the impulse of `u` partners inside their step
    /// receive, in units of `1 / inv_quantum`.
    pub gains: &'a [AtomicI64],
    /// The fixed point's scale.
    pub inv_quantum: f64,
}

/// A group of targets' side of the conduction sum: `K/h_i^4`, `rho_i`,
/// `P_i`, `u_i`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConductionTarget {
    pub(crate) ki4: F64s,
    pub(crate) rho: F64s,
    pub(crate) p: F64s,
    pub(crate) u: F64s,
    pub(crate) contrast: Contrast,
    /// With impulses: the targets' time since their last kick, their
    /// masses and the lanes whose sums are kept.
    since: F64s,
    m: F64s,
    lanes: u32,
}

impl ConductionTarget {
    /// The targets of `g` with `1/h` = `inv_hi` (`m`: the masses, read
    /// with impulses).
    #[inline(always)]
    pub(crate) fn load(
        g: &Group,
        norm: f64,
        inv_hi: F64s,
        rho: &[f64],
        m: &[f64],
        c: &Conductivity<'_>,
    ) -> Self {
        let ih2 = inv_hi * inv_hi;
        let zero = F64s::splat(0.0);
        let (since, m) = c
            .impulses
            .map_or((zero, zero), |w| (g.load(w.since), g.load(m)));
        Self {
            ki4: norm * (ih2 * ih2),
            rho: g.load(rho),
            p: g.load(c.p),
            u: g.load(c.u),
            contrast: c.contrast,
            since,
            m,
            lanes: g.active,
        }
    }

    /// Partner `j`'s `term` as the targets' sum takes it: as is (a rate),
    /// or with [`Conductivity::impulses`] times the time since the pair's
    /// last exchange, the partner's side going to its gains where it is
    /// inside its step. `m_j` is the partner's mass.
    #[inline(always)]
    pub(crate) fn weigh(&self, c: &Conductivity<'_>, j: usize, m_j: f64, term: F64s) -> F64s {
        let Some(w) = &c.impulses else {
            return term;
        };
        let flux = term * self.since.min(F64s::splat(w.since[j]));
        if !w.starts[j] && m_j > 0.0 {
            // -alpha_u m_i (term / m_j) dt per kept lane, each rounded on
            // its own (the lanes' grouping differs with the rank count).
            let gain = (-c.alpha_u / m_j * w.inv_quantum) * flux * self.m;
            let mut q = 0i64;
            for (l, g) in gain.to_array().into_iter().enumerate() {
                if self.lanes & (1 << l) != 0 {
                    q = q.wrapping_add(g.round() as i64);
                }
            }
            if q != 0 {
                w.gains[j].fetch_add(q, Ordering::Relaxed);
            }
        }
        flux
    }

    /// `dW = (K/h_i^4 w'(r/h_i) + K/h_j^4 w'(r/h_j)) / 2` at the squared
    /// distance `r2` (zero beyond both supports and at `r = 0`).
    #[inline(always)]
    pub(crate) fn mean_derivative<K: Kernel>(
        &self,
        kernel: &K,
        norm: f64,
        r2: F64s,
        inv_hi: F64s,
        inv_hj: f64,
    ) -> F64s {
        let r = r2.sqrt();
        let kj4 = norm * inv_hj.powi(4);
        let wi = kernel.shape_and_derivative_lanes(r * inv_hi).1;
        let wj = kernel.shape_and_derivative_lanes(r * inv_hj).1;
        0.5 * (self.ki4 * wi + kj4 * wj)
    }

    /// Partner `j`'s term of the sum (before the factor `alpha_u`),
    /// `m_j v_u (u_i - u_j) / rho_ij dW`, for the mean kernel derivative
    /// `dW` ([`mean_derivative`](Self::mean_derivative)), times the
    /// pair's [`Contrast`]. A zero mass or `dW` (partners beyond both
    /// supports) gives an exact zero.
    #[inline(always)]
    pub(crate) fn term(&self, m_j: F64s, dw: F64s, rho_j: f64, p_j: f64, u_j: f64) -> F64s {
        let rho_ij = 0.5 * (self.rho + rho_j);
        let dp = self.p - p_j;
        let v_u = (dp.abs() / rho_ij).sqrt();
        let du = self.u - u_j;
        let flux = m_j * v_u * du / rho_ij * dw;
        // A top of 0 only where both values are 0, and then the jump is 0.
        let tiny = F64s::splat(f64::MIN_POSITIVE);
        let of_u = || du.abs() / self.u.max(F64s::splat(u_j)).max(tiny);
        let of_p = || {
            let top = self.p.abs().max(F64s::splat(p_j.abs())).max(tiny);
            (dp.abs() / top).min(F64s::splat(1.0))
        };
        match self.contrast {
            Contrast::Off => flux,
            Contrast::Energy => flux * of_u(),
            Contrast::Pressure => flux * of_p(),
            Contrast::Larger => flux * of_u().max(of_p()),
        }
    }
}

/// The conduction sums as a pass of their own.
struct Conduction<'a, K> {
    kernel: &'a K,
    norm: f64,
    h: &'a [f64],
    m: &'a [f64],
    rho: &'a [f64],
    c: Conductivity<'a>,
}

impl<K: Kernel> PairStage for Conduction<'_, K> {
    type Sums = (F64s, ConductionTarget, F64s);
    type Out<'o> = [&'o mut [f64]; 1];
    type Stats = ();

    #[inline(always)]
    fn start(&self, g: &Group) -> Self::Sums {
        let inv_hi = 1.0 / g.load(self.h);
        let target = ConductionTarget::load(g, self.norm, inv_hi, self.rho, self.m, &self.c);
        (inv_hi, target, F64s::splat(0.0))
    }

    #[inline(always)]
    fn pair(&self, (inv_hi, target, sum): &mut Self::Sums, j: usize, _: [F64s; 3], r2: F64s) {
        let (c, inv_hj) = (&self.c, 1.0 / self.h[j]);
        let dw = target.mean_derivative(self.kernel, self.norm, r2, *inv_hi, inv_hj);
        let m_j = F64s::splat(self.m[j]);
        *sum += target.term(m_j, dw, self.rho[j], c.p[j], c.u[j]);
    }

    #[inline(always)]
    fn finish(&self, _: &Group, (_, _, sum): Self::Sums, [du]: &mut Self::Out<'_>) {
        let add = (self.c.alpha_u * sum).to_array();
        for (d, a) in du.iter_mut().zip(add) {
            *d += a;
        }
    }
}
