//! Rotating square patch, 20^3 particles for 300 steps: angular momentum,
//! linear momentum and no tensile clumping.

use sph_apps::cases::{self, square_patch};
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn square_patch_conserves_angular_momentum_without_clumping() {
    let scene = cases::lookup("square-patch")
        .unwrap()
        .setup(20, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("square_patch20");
    let s = sph_validation::run(scene, Stop::Steps(300), &out);
    let [l0, l1] = s.angular_momentum_z;
    // The lattice carries the continuum value rho omega H L^4 / 6 up to
    // its discretisation (sum of x^2 + y^2 over cell centres: -0.25% at 20^2).
    let exact = square_patch::angular_momentum_exact();
    assert!(
        ((-l0) - exact).abs() < 5e-3 * exact,
        "L_z = {l0:e}, continuum {exact:e}"
    );
    // Pairwise forces are central-symmetric: L_z is conserved to integrator accuracy.
    assert!(
        ((l1 - l0) / l0).abs() < 1e-3,
        "L_z drift {:e}",
        (l1 - l0) / l0
    );
    assert!(
        s.momentum_rel_drift < 1e-12,
        "momentum drift {:e}",
        s.momentum_rel_drift
    );
    // No particle pair closer than a tenth of the initial spacing (5 cm).
    assert!(
        s.min_pair_distance > 0.5,
        "closest pair {}",
        s.min_pair_distance
    );
}
