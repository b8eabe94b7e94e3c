//! The pressure-gradient term's particle volumes: [`Volume`] (what a
//! scheme asks for), [`VolumeWeights`] (the elements a pass is given) and
//! the per-pair weights each kind puts on the pressure terms.

use crate::choice::Choice;
use crate::pair_loop::{F64s, Group, LANES};
use serde::{Deserialize, Serialize};

/// The particle volumes the sums are built with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Volume {
    /// `V_j = m_j / rho_j` with `rho_i = sum_j m_j W_ij` (the seed paper).
    #[default]
    Mass,
    /// SPH-EXA's generalised volume elements ("ve"): `X_i = m_i / rho0_i`
    /// with the standard density `rho0_i`, the normalisation
    /// `k_i = sum_j X_j W_ij`, the density `rho_i = k_i m_i / X_i`, volumes
    /// `V_j = X_j / k_j` in grad-h and IAD, and momentum weights blended
    /// from `X_i^2, X_j^2` to `X_i X_j` by the Atwood number
    /// ([`density::ve_density`](crate::density::ve_density),
    /// [`momentum`](crate::momentum)).
    Generalised,
    /// Pressure-energy volumes (Saitoh & Makino 2013, Hopkins 2013):
    /// `X_i = m_i u_i`, so `k_i = sum_j m_j u_j W_ij` is the smoothed
    /// `P / (gamma - 1)` and stays smooth across a contact discontinuity
    /// where the mass-weighted density jumps; `rho_i = k_i m_i / X_i`,
    /// volumes `V_j = X_j / k_j`, and the momentum and energy equations
    /// in Hopkins's scale-free form (pair weights `X_i X_j / (k_i^2 m_i)`,
    /// see [`momentum`](crate::momentum)). For contacts and shear layers
    /// in pressure equilibrium (isobaric cube, Kelvin-Helmholtz); it needs
    /// `u > 0` everywhere.
    PressureEnergy,
}

/// `--volume` and the `volume` key.
impl Choice for Volume {
    const ALL: &'static [Self] = &[Volume::Mass, Volume::Generalised, Volume::PressureEnergy];

    fn name(&self) -> &'static str {
        match self {
            Volume::Mass => "mass",
            Volume::Generalised => "ve",
            Volume::PressureEnergy => "pressure-energy",
        }
    }

    fn help(&self) -> &'static str {
        match self {
            Volume::Mass => "m / rho: the seed paper's",
            Volume::Generalised => {
                "SPH-EXA's generalised volume elements, X = m / rho0 (needs IAD)"
            }
            Volume::PressureEnergy => {
                "Pressure-energy volumes, X = m u: a pressure that stays smooth across contact \
                 discontinuities (needs u > 0)"
            }
        }
    }
}

/// The particle volumes the momentum and energy equations weigh pairs
/// with (see [`momentum_energy_with`](super::momentum_energy_with)).
#[derive(Debug, Clone, Copy)]
pub enum VolumeWeights<'a> {
    /// `m / rho`: the paper's equations.
    Mass,
    /// SPH-EXA's generalised volume elements `X` (every particle), with
    /// the Atwood-blended weights.
    Atwood(&'a [f64]),
    /// Volume elements `X` (every particle) in Hopkins's (2013)
    /// scale-free form: pair weights `X_i X_j`.
    Product(&'a [f64]),
}

impl<'a> VolumeWeights<'a> {
    /// The weights of `volume` with the elements `xm` (unused for
    /// [`Volume::Mass`]).
    pub fn of(volume: Volume, xm: &'a [f64]) -> Self {
        match volume {
            Volume::Mass => Self::Mass,
            Volume::Generalised => Self::Atwood(xm),
            Volume::PressureEnergy => Self::Product(xm),
        }
    }

    pub(super) fn elements(&self) -> Option<&'a [f64]> {
        match *self {
            Self::Mass => None,
            Self::Atwood(x) | Self::Product(x) => Some(x),
        }
    }
}

/// The weights `(a_ij, b_ij)` one kind of volume puts on the pressure
/// terms `P_i/.. A_ij(h_i)` and `P_j/.. A_ij(h_j)` of a pair
/// (compile-time dispatch).
pub(crate) trait PressureWeights: Sync {
    /// What a group of targets loads once.
    type Target: Copy;
    /// The targets' values.
    fn target(&self, g: &Group) -> Self::Target;
    /// `(a_ij, b_ij)` of the targets with partner `j`.
    fn pair(&self, t: &Self::Target, j: usize) -> (F64s, F64s);
}

/// `m / rho`: weights 1 (the multiplications by 1 are exact, and the
/// compiler drops them).
pub(crate) struct Mass;

impl PressureWeights for Mass {
    type Target = ();

    #[inline(always)]
    fn target(&self, _g: &Group) {}

    #[inline(always)]
    fn pair(&self, _t: &(), _j: usize) -> (F64s, F64s) {
        (F64s::splat(1.0), F64s::splat(1.0))
    }
}

/// SPH-EXA's Atwood-blended weights of the volume elements `x`, with the
/// densities `rho` (both cut to the state).
pub(crate) struct Atwood<'a> {
    pub(crate) rho: &'a [f64],
    pub(crate) x: &'a [f64],
}

/// The targets' density, `X` and `ln X`.
#[derive(Clone, Copy)]
pub(crate) struct AtwoodTarget {
    rho: F64s,
    x: F64s,
    ln_x: F64s,
}

impl PressureWeights for Atwood<'_> {
    type Target = AtwoodTarget;

    #[inline(always)]
    fn target(&self, g: &Group) -> AtwoodTarget {
        AtwoodTarget {
            rho: g.load(self.rho),
            x: g.load(self.x),
            ln_x: F64s::from_array(g.load(self.x).to_array().map(f64::ln)),
        }
    }

    #[inline(always)]
    fn pair(&self, t: &AtwoodTarget, j: usize) -> (F64s, F64s) {
        atwood_weights(t.rho, self.rho[j], t.x, t.ln_x, self.x[j])
    }
}

/// Hopkins's scale-free weights `X_i X_j / m_j` and, for the `j` side,
/// `X_i X_j / m_i`, of the elements `x` with the masses `m`.
pub(crate) struct Product<'a> {
    pub(crate) m: &'a [f64],
    pub(crate) x: &'a [f64],
}

impl PressureWeights for Product<'_> {
    /// `X_i` and `1 / m_i`.
    type Target = (F64s, F64s);

    #[inline(always)]
    fn target(&self, g: &Group) -> (F64s, F64s) {
        (g.load(self.x), F64s::splat(1.0) / g.load(self.m))
    }

    #[inline(always)]
    fn pair(&self, &(x_i, inv_m_i): &(F64s, F64s), j: usize) -> (F64s, F64s) {
        let cross = x_i * self.x[j];
        (cross * (1.0 / self.m[j]), cross * inv_m_i)
    }
}

/// Atwood numbers below this keep the weights `X_i^2, X_j^2`.
const ATWOOD_MIN: f64 = 0.1;
/// Atwood numbers above this use the weights `X_i X_j`.
const ATWOOD_MAX: f64 = 0.2;

/// SPH-EXA's momentum weights `(a_ij, b_ij)` of pair `i, j` from the
/// Atwood number of the densities and the volume elements (see
/// [`momentum_energy_with`](super::momentum_energy_with); `ln_xi` holds
/// `ln X_i`); `b_ij` of `i, j` is bit for bit `a_ji`, so the pair terms
/// stay antisymmetric.
#[inline(always)]
fn atwood_weights(rho_i: F64s, rho_j: f64, xi: F64s, ln_xi: F64s, xj: f64) -> (F64s, F64s) {
    let rho_j = F64s::splat(rho_j);
    // At < c as |rho_i - rho_j| < c (rho_i + rho_j): no division per pair
    // (the divider is the pair loop's scarcest unit).
    let (jump, sum) = ((rho_i - rho_j).abs(), rho_i + rho_j);
    let xj_l = F64s::splat(xj);
    let cross = xi * xj_l;
    let low = jump.lt(ATWOOD_MIN * sum);
    let high = jump.gt(ATWOOD_MAX * sum);
    let mut a = low.select(xi * xi, cross);
    let mut b = low.select(xj_l * xj_l, cross);
    if !(low | high).all() {
        // The ramp, lane by lane (interfaces, and wherever the density
        // varies by more than ~20% over a kernel: Evrard's whole sphere).
        // X_i^(2-s) X_j^s = X_i^2 exp(s d) with d = ln X_j - ln X_i: two
        // exponentials per lane where four powers cost a quarter of an
        // Evrard step. With i and j swapped d changes sign exactly, so
        // b_ij = X_j^2 exp(-s d) is a_ji bit for bit.
        let at_l = (jump / sum).to_array();
        // Lanes on the ramp: neither below nor above it.
        let on_ramp = !(low | high).bits();
        let (xi_l, ln_xi_l) = (xi.to_array(), ln_xi.to_array());
        let (mut al, mut bl) = (a.to_array(), b.to_array());
        let (ramp, ln_xj, xj2) = (1.0 / (ATWOOD_MAX - ATWOOD_MIN), xj.ln(), xj * xj);
        for l in 0..LANES {
            if on_ramp & (1 << l) != 0 {
                let s = (ramp * (at_l[l] - ATWOOD_MIN)).clamp(0.0, 1.0);
                let sd = s * (ln_xj - ln_xi_l[l]);
                al[l] = xi_l[l] * xi_l[l] * sd.exp();
                bl[l] = xj2 * (-sd).exp();
            }
        }
        a = F64s::from_array(al);
        b = F64s::from_array(bl);
    }
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The Atwood weights are SPH-EXA's `X_i^(2-s) X_j^s` (to
        /// round-off) and `b_ij` is `a_ji` bit for bit, on and off the
        /// ramp.
        #[test]
        fn atwood_weights_are_the_blend_and_antisymmetric(
            rho in proptest::collection::vec(0.1f64..10.0, LANES + 1),
            x in proptest::collection::vec(1e-6f64..1.0, LANES + 1),
        ) {
            let rho_i = F64s::from_array(std::array::from_fn(|l| rho[l]));
            let x_i = F64s::from_array(std::array::from_fn(|l| x[l]));
            let ln_x_i = F64s::from_array(x_i.to_array().map(f64::ln));
            let (rho_j, x_j) = (rho[LANES], x[LANES]);
            let (a, b) = atwood_weights(rho_i, rho_j, x_i, ln_x_i, x_j);
            let (a, b) = (a.to_array(), b.to_array());
            for l in 0..LANES {
                let at = (rho[l] - rho_j).abs() / (rho[l] + rho_j);
                let s = ((at - ATWOOD_MIN) / (ATWOOD_MAX - ATWOOD_MIN)).clamp(0.0, 1.0);
                let want = x[l].powf(2.0 - s) * x_j.powf(s);
                prop_assert!((a[l] - want).abs() <= 1e-13 * want, "a {} vs {want} at At {at}", a[l]);
                // The pair seen from j: one lane holding j, partner i.
                let (a_ji, _) = atwood_weights(
                    F64s::splat(rho_j),
                    rho[l],
                    F64s::splat(x_j),
                    F64s::splat(x_j.ln()),
                    x[l],
                );
                prop_assert_eq!(b[l].to_bits(), a_ji.to_array()[0].to_bits());
            }
        }

        /// The scale-free weights are antisymmetric bit for bit: `b_ij`
        /// is `a_ji`.
        #[test]
        fn product_weights_are_antisymmetric(
            m in proptest::collection::vec(0.1f64..10.0, 2),
            x in proptest::collection::vec(1e-6f64..1.0, 2),
        ) {
            let w = Product { m: &m, x: &x };
            let load = |k: usize| (F64s::splat(x[k]), F64s::splat(1.0) / F64s::splat(m[k]));
            let (a_ij, b_ij) = w.pair(&load(0), 1);
            let (a_ji, b_ji) = w.pair(&load(1), 0);
            prop_assert_eq!(b_ij.to_array()[0].to_bits(), a_ji.to_array()[0].to_bits());
            prop_assert_eq!(b_ji.to_array()[0].to_bits(), a_ij.to_array()[0].to_bits());
        }
    }
}
