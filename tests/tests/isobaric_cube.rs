//! The isobaric cube (rho 8 inside, 1 outside, P = 2.5, periodic) to
//! t = 1 (two sound crossings of the box in the thin gas), with the case's
//! scheme (`contact`: pressure-energy volumes, kernel gradients), at 16
//! and 32 thin particles per side (7,680 and 61,440 particles).
//!
//! The exact solution is the initial state, so there is no null solution
//! to reject: the checks are how far the run strays from it. The lattices'
//! contact launches waves that fill the box and decay; v_rms / mean c at
//! t = 1, measured (2 threads): 0.0178 at 16, 0.0104 at 24, 0.0085 at 32
//! with this scheme; the paper's scheme (volumes m / rho, IAD) 0.067 at 16
//! and 0.062 at 24, SPH-EXA's `ve` 0.049 and 0.044. The bounds:
//! VALIDATION's goal v_rms / c < 1e-2 at 32, the error falling from 16 to
//! 32, and the cube itself in place (core rho ~ 8, thin gas rho ~ 1).
//!
//! The flow is chaotic: positions perturbed by 1e-9 of the spacing end at
//! v_rms / c 0.0098-0.0100 at 32 (four seeds, README: the isobaric cube's
//! caveat), under the goal in every realisation measured but with 0-2% to
//! spare; the exact lattice's run, the one checked here, is the quietest.

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

/// v_rms / mean c at t = 1 and the mean densities of the core (max-norm
/// radius < 0.15) and of the thin gas far from the cube (> 0.35).
fn run(side: usize) -> (f64, f64, f64) {
    let scene = cases::lookup("isobaric-cube")
        .unwrap()
        .setup(side, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("isobaric{side}"));
    let s = sph_validation::run_writing_particles(scene, Stop::Time(1.0), &out);
    assert!(s.energy_rel_drift.abs() < 1e-3, "{}", s.energy_rel_drift);
    assert!(s.momentum_rel_drift < 1e-12, "{}", s.momentum_rel_drift);

    let p = sph_validation::read_particles(&out);
    let gamma = cases::isobaric_cube::GAMMA;
    let n = p["x"].len();
    let (mut v2, mut c) = (0.0, 0.0);
    let (mut core, mut n_core, mut far, mut n_far) = (0.0, 0, 0.0, 0);
    for i in 0..n {
        assert!(p["u"][i] > 0.0 && p["rho"][i].is_finite());
        v2 += p["vx"][i].powi(2) + p["vy"][i].powi(2) + p["vz"][i].powi(2);
        c += (gamma * p["p"][i] / p["rho"][i]).sqrt();
        let r = [p["x"][i], p["y"][i], p["z"][i]]
            .iter()
            .fold(0.0f64, |m, q| m.max(q.abs()));
        if r < 0.15 {
            core += p["rho"][i];
            n_core += 1;
        } else if r > 0.35 {
            far += p["rho"][i];
            n_far += 1;
        }
    }
    let ratio = (v2 / n as f64).sqrt() / (c / n as f64);
    (ratio, core / n_core as f64, far / n_far as f64)
}

#[test]
fn isobaric_cube_stays_put() {
    let (coarse, _, _) = run(16);
    let (fine, core, far) = run(32);
    println!("v_rms / c: {coarse} at 16, {fine} at 32");
    assert!(fine < 1e-2, "v_rms / c = {fine} at 32 (goal 1e-2)");
    assert!(
        fine < 0.8 * coarse,
        "no convergence: {coarse} at 16, {fine} at 32"
    );
    assert!((core / 8.0 - 1.0).abs() < 0.05, "core density {core}");
    assert!((far - 1.0).abs() < 0.05, "thin gas density {far}");
}
