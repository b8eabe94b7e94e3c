//! The viscosity strength `alpha_ij` of a pair: one constant, or the mean
//! of per-particle switches ([`av_switch`](crate::av_switch)).

use crate::pair_loop::{F64s, Group};

/// How a pair's viscosity strength is made (compile-time dispatch).
pub(crate) trait Strength: Sync {
    /// The strength the targets of `g` bring.
    fn target(&self, g: &Group) -> F64s;
    /// `alpha_ij` of the targets (their [`target`](Self::target) values
    /// `alpha_i`) with partner `j`.
    fn pair(&self, alpha_i: F64s, j: usize) -> F64s;
}

/// One strength for every pair.
pub(crate) struct Constant(pub(crate) f64);

impl Strength for Constant {
    #[inline(always)]
    fn target(&self, _g: &Group) -> F64s {
        F64s::splat(self.0)
    }

    #[inline(always)]
    fn pair(&self, _alpha_i: F64s, _j: usize) -> F64s {
        F64s::splat(self.0)
    }
}

/// A strength per particle (targets and halos); pairs take the mean, so
/// `alpha_ij = alpha_ji`.
pub(crate) struct Mean<'a>(pub(crate) &'a [f64]);

impl Strength for Mean<'_> {
    #[inline(always)]
    fn target(&self, g: &Group) -> F64s {
        g.load(self.0)
    }

    #[inline(always)]
    fn pair(&self, alpha_i: F64s, j: usize) -> F64s {
        0.5 * (alpha_i + self.0[j])
    }
}
