//! Sedov-Taylor blast wave, 30^3 particles to t = 0.05, against the
//! similarity solution.

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn sedov_30_cubed_matches_similarity_solution() {
    let scene = cases::lookup("sedov")
        .unwrap()
        .setup(30, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("sedov30");
    let s = sph_validation::run(scene, Stop::Time(0.05), &out);
    let r = s.shock_radius.unwrap();
    let r_ref = s.shock_radius_ref.unwrap();
    // Reference value of VALIDATION.md, computed independently.
    assert!(
        (r_ref - 0.3475).abs() < 1e-3,
        "reference shock radius {r_ref}"
    );
    // The densest radial bin lies within 5% of the analytic shock.
    assert!(
        (r - r_ref).abs() < 0.05 * r_ref,
        "shock at {r}, reference {r_ref}"
    );
    // SPH smooths the jump: the peak stays below the strong-shock limit 4.
    assert!(s.peak_density < 4.0, "peak density {}", s.peak_density);
    assert!(
        s.peak_density > 1.8,
        "no shock formed: peak density {}",
        s.peak_density
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
    // L1 over all particles. Against flat fields (rho = 1, p = 0, v = 0)
    // the reference scores 0.147, 0.478 and 0.242 (integrals of |f_ref| or
    // |1 - rho_ref| over the box), so L1(rho) alone hardly discriminates:
    // SPH's smoothed shell costs as much as it gains. The C++ SPH-EXA `std`
    // scheme reaches L1(rho) = 0.149 here; this run measures rho 0.151,
    // p 0.273, |v| 0.159. Bounds: ~10% above the measured values, which a
    // run without a correct blast (flat fields) cannot meet for p and v.
    let l1 = s.l1.unwrap();
    assert!(l1.rho < 0.165, "L1(rho) = {}", l1.rho);
    assert!(l1.p < 0.30, "L1(p) = {}", l1.p);
    assert!(l1.v < 0.18, "L1(|v|) = {}", l1.v);
}
