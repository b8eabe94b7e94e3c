//! Kelvin-Helmholtz instability (McNally et al. 2012 set-up), 32 x 32 x 8
//! particles, to t = 1.5, with the case's scheme (`ve`): the seeded mode
//! must grow.
//!
//! Measured M(t) at 32^2 (2 threads): 0.0100 at the start, a dip to 0.0055
//! near t = 0.47 while the seed reorganises, then growth: 0.0138 at t = 1.0,
//! 0.0219 at t = 1.5. McNally's converged reference is M(1.5) = 0.1479;
//! SPH of the SPH-EXA family reaches 0.029 with alpha = 1 and 0.083 with
//! switches (at their resolutions, VALIDATION.md). The checks: M grows
//! past 1.5x the seed by t = 1.5 and rises over the last third of the run;
//! the null solution (nothing happens) keeps M = 0.01 and fails both.

use sph_apps::cases;
use sph_apps::simulation::Stop;
use sph_core::HydroConfig;

#[test]
fn kelvin_helmholtz_mode_grows() {
    let scene = cases::lookup("kelvin-helmholtz")
        .unwrap()
        .setup(32, HydroConfig::default())
        .unwrap();
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("kh32");
    let s = sph_validation::run(scene, Stop::Time(1.5), &out);
    assert!(s.energy_rel_drift.abs() < 1e-3, "{}", s.energy_rel_drift);
    assert!(s.momentum_rel_drift < 1e-12, "{}", s.momentum_rel_drift);

    let text = std::fs::read_to_string(out.join("curve.csv")).unwrap();
    let m: Vec<(f64, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').skip(1).map(|v| v.parse().unwrap()).collect();
            (f[0], f[1])
        })
        .collect();
    let seed = cases::kelvin_helmholtz::SEED;
    let (t_end, m_end) = *m.last().unwrap();
    assert!((t_end - 1.5).abs() < 1e-9, "last line at t = {t_end}");
    assert!((m[0].1 / seed - 1.0).abs() < 0.01, "M starts at {}", m[0].1);
    assert!(m_end > 1.5 * seed, "M(1.5) = {m_end}");
    let at_one = m.iter().find(|(t, _)| *t >= 1.0).unwrap().1;
    assert!(m_end > at_one, "M(1.0) = {at_one}, M(1.5) = {m_end}");
    println!("M(1.5) = {m_end}");
}
