//! The rotating square patch in the seed paper's layout: `side x side`
//! particles in the plane (100 x 100 by default) and a thin periodic slab
//! of [`LAYERS`] layers in z, with the scheme, EOS and set-up of
//! [`square-patch`](super::square_patch) otherwise.

use super::square_patch::{angular_momentum_curve, patch_state, SquarePatch};
use super::{Request, Case, Curve, InitialState, Listing, Physics, Scheme};
use crate::AppError;

/// The case (registered as `square-patch-slab`).
#[derive(Debug, Clone, Copy)]
pub struct SquarePatchSlab;

/// Particle layers in z: the slab is `LAYERS L / side` thick, more than
/// twice the kernel's reach (about 2.9 spacings at 100 neighbours), as the
/// periodic search needs.
pub const LAYERS: usize = 8;

impl Case for SquarePatchSlab {
    fn listing(&self) -> Listing {
        Listing {
            name: "square-patch-slab",
            description: "Rotating square patch in the paper's layout: side x side in the plane, 8 periodic layers in z",
            side: 100,
            end_time: 0.5,
        }
    }

    /// That of [`SquarePatch`].
    fn default_scheme(&self) -> Scheme {
        SquarePatch.default_scheme()
    }

    /// That of [`SquarePatch`].
    fn physics(&self) -> Physics {
        SquarePatch.physics()
    }

    /// `side x side` particles per layer, [`LAYERS`] layers.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        let Request { side, config, share, .. } = *request;
        patch_state(side, LAYERS, config, share)
    }

    /// `-L_z` scaled to a slab 100 cm thick, as [`SquarePatch`]'s.
    fn curve(&self) -> Option<Curve> {
        Some(angular_momentum_curve())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_core::HydroConfig;

    /// The curve's `-L_z` of a slab `L` thick: the same for the thin slab
    /// and the cube of the same in-plane lattice, and within the lattice's
    /// discretisation (-0.25% at 20^2) of the continuum's 8.3333e9.
    #[test]
    fn slab_and_cube_start_with_the_same_scaled_angular_momentum() {
        let value = |case: &dyn Case| {
            let scene = case.setup(20, HydroConfig::default()).unwrap();
            let curve = case.curve().unwrap();
            let p = &scene.particles;
            let mut sums = vec![0.0; curve.sums];
            let mut t = vec![0.0; curve.sums];
            for i in 0..p.len() {
                (curve.terms)(p, i, &mut t);
                sums.iter_mut().zip(&t).for_each(|(s, v)| *s += v);
            }
            ((curve.finish)(&sums)[0], p.len())
        };
        let (slab, n_slab) = value(&SquarePatchSlab);
        let (cube, n_cube) = value(&SquarePatch);
        assert_eq!((n_slab, n_cube), (20 * 20 * LAYERS, 20 * 20 * 20));
        assert!((slab / cube - 1.0).abs() < 1e-12, "{slab:e} vs {cube:e}");
        let exact = super::super::square_patch::ANGULAR_MOMENTUM_EXACT;
        assert!((slab / exact - 1.0).abs() < 3e-3, "{slab:e} vs {exact:e}");
    }
}
