//! Noh implosion to t = 0.3 with the case's scheme (`gas`, the ideal-gas
//! cases' default since 2026-12-06: viscosity switches up to alpha = 0.3
//! at shocks into cold gas, AV cleaning, conduction across the larger of
//! the contrasts of u and of pressure), at two resolutions: spheres cut from 37^3 and 44^3 lattices (26,745
//! and 44,720 particles; global time steps at 37^3 only). The figures of the `noh` preset (kernel
//! gradients, switches up to 0.7), the case's scheme before, follow each
//! `gas` figure in brackets; the bounds were set on it.
//!
//! - **Plateau.** The mean density between 0.3 and 0.8 shock radii (the
//!   centre has the wall-heating dip, the outer part the smeared shock)
//!   within 5% of the analytic 64 rho0 (rho0 the particle set's own
//!   density) at both. Measured (2 threads, 2026-12-07, evening, global
//!   steps at 37^3): 123.5 against 121.2, +1.9% (`noh` 125.4 / 121.4 at
//!   37^3 / 44^3). The initial state has rho0 there, -98%.
//! - **Shock radius** (half-way density between the inflow and the shocked
//!   gas) within 10% of the analytic 0.1: measured 0.0983 (0.0957 /
//!   0.0981).
//! - **L1 errors near the shock**, over the particles inside 1.2 shock
//!   radii against the analytic solution (rho, P, |v|; absolute units,
//!   64 rho0 = 122). Measured: 23.25 / 10.12 / 0.317 at 37^3 (26.46 /
//!   14.54 / 0.328, and 26.17 / 14.79 / 0.323 at 44^3).
//!   Bounds: the larger of the `noh` figures plus 10%. The
//!   untouched initial state (rho0, P = 0 and the inflow speed 1
//!   everywhere) scores 77.3 / 22.5 / 0.553 at 37^3 and 79.6 / 23.4 /
//!   0.577 at 44^3 (computed in the test), over every bound. Over all the
//!   particles, or inside 1.5 shock radii, it would not: there most
//!   particles of the untouched state sit in the unshocked inflow, which
//!   it describes exactly (inside 1.5 shock radii it scores 11.1 / 0.273
//!   on P and |v| against the run's 12.0 / 0.289 at 37^3).
//! - Energy conserved to 1e-3, momentum to 1e-12 (1e-6 under block time
//!   steps, the second test).

use sph_apps::cases::Reference;
use sph_apps::simulation::Stop;
use sph_apps::Summary;
use sph_core::Particles;
use std::collections::HashMap;

const T_END: f64 = 0.3;
/// The L1 errors are taken inside this many shock radii.
const NEAR_SHOCK: f64 = 1.2;
/// L1 bounds inside [`NEAR_SHOCK`] shock radii: rho, P, |v|.
const L1_MAX: [f64; 3] = [29.1, 16.3, 0.36];

/// L1 of rho, P and |v| against `reference` at `T_END` over the particles
/// inside [`NEAR_SHOCK`] shock radii.
fn l1_near_shock(reference: &Reference, p: &HashMap<String, Vec<f64>>) -> [f64; 3] {
    let edge = NEAR_SHOCK * reference.shock_radius(T_END).expect("a shock");
    let (mut l1, mut n) = ([0.0; 3], 0usize);
    for i in 0..p["x"].len() {
        let r = reference.coordinate([p["x"][i], p["y"][i], p["z"][i]]);
        if r >= edge {
            continue;
        }
        let s = reference.state(r, T_END);
        let speed = (p["vx"][i].powi(2) + p["vy"][i].powi(2) + p["vz"][i].powi(2)).sqrt();
        l1[0] += (p["rho"][i] - s.rho).abs();
        l1[1] += (p["p"][i] - s.p).abs();
        l1[2] += (speed - s.v.abs()).abs();
        n += 1;
    }
    assert!(n > 100, "{n} particles inside {NEAR_SHOCK} shock radii");
    l1.map(|v| v / n as f64)
}

/// The untouched initial state `p` with density `rho0` and no pressure,
/// as columns.
fn untouched(p: &Particles, rho0: f64) -> HashMap<String, Vec<f64>> {
    let n = p.len();
    [
        ("x", p.x.clone()),
        ("y", p.y.clone()),
        ("z", p.z.clone()),
        ("vx", p.vx.clone()),
        ("vy", p.vy.clone()),
        ("vz", p.vz.clone()),
        ("rho", vec![rho0; n]),
        ("p", vec![0.0; n]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v))
    .collect()
}

/// The run's summary, its L1 near the shock and the untouched state's.
fn run(side: usize, time_steps: sph_core::TimeSteps) -> (Summary, [f64; 3], [f64; 3]) {
    let mut scene = sph_validation::scene("noh", side);
    scene.config.time_steps = time_steps;
    let reference = scene.reference.clone().expect("noh has a reference");
    // The inflow's density at t = 0 is the particle set's rho0.
    let rho0 = reference.state(1.0, 0.0).rho;
    let null = l1_near_shock(&reference, &untouched(&scene.particles, rho0));
    let name = sph_core::Choice::name(&time_steps);
    let out = sph_validation::scratch(&format!("noh{side}-{name}"));
    let s = sph_validation::run_writing_particles(scene, Stop::Time(T_END), &out);
    let l1 = l1_near_shock(&reference, &sph_validation::read_particles(&out));
    println!(
        "{side}^3: plateau {:?} (target {:?}), shock {:?}, L1 near the shock {l1:?}, untouched {null:?}",
        s.plateau_density, s.plateau_density_ref, s.shock_radius
    );
    (s, l1, null)
}

/// Global time steps at 37^3 only: the default, block steps (the next
/// test), holds the bounds at both resolutions, and the global run at
/// 44^3 (35 M particle updates, half of this file's work) was cut to keep
/// CI inside its time (2026-12-07; it measured 16.01 / 7.22 / 0.230).
#[test]
fn noh_reaches_the_plateau_under_global_time_steps() {
    let (s, l1, null) = run(37, sph_core::TimeSteps::Global);
    check(37, &s, l1, null, 1e-12);
}

/// Block time steps (issue 41, the default) at both resolutions, at the
/// same bounds but momentum: a pair's two forces are evaluated at different times, so it
/// holds to 1e-6 (measured 2.7e-8 and 6.7e-8 with `noh`). Measured with
/// `gas` (2026-12-07, evening): plateau 122.8 / 122.1 (+1.3% / +0.1%),
/// shock 0.0993 / 0.1006, L1 near the shock 22.41 / 9.82 / 0.307 and
/// 14.73 / 6.84 / 0.227 (2026-12-06, strong-shock ceiling 0.4 and the
/// contrast of u alone: 118.1 / 116.4, -2.6% / -4.5%). With `noh` (2026-12-04):
/// plateau 123.7 / 122.4 (+2.1% / +0.4%), shock 0.0958 / 0.0999, energy
/// drift 1.7e-4 / 1.2e-4, L1 near the shock 25.36 / 13.88 / 0.320 and
/// 25.95 / 13.49 / 0.304 (lower than the global runs'), particle updates
/// 0.28 / 0.27 of the global run's (4.92 M against 17.4 M, 9.46 M
/// against 35.3 M; wall 0.55x / 0.51x).
#[test]
fn noh_reaches_the_plateau_under_block_time_steps() {
    for side in [37, 44] {
        let (s, l1, null) = run(side, sph_core::TimeSteps::Block);
        check(side, &s, l1, null, 1e-6);
    }
}

/// The bounds of the module's text, momentum to `momentum`.
fn check(side: usize, s: &Summary, l1: [f64; 3], null: [f64; 3], momentum: f64) {
    let target = s.plateau_density_ref.unwrap();
    let plateau = s.plateau_density.unwrap();
    assert!(
        (plateau / target - 1.0).abs() < 0.05,
        "{side}^3: plateau {plateau} = {} x 64 rho0",
        plateau / target
    );
    let (r, r_ref) = (s.shock_radius.unwrap(), s.shock_radius_ref.unwrap());
    assert!((r_ref - 0.1).abs() < 1e-12, "reference shock at {r_ref}");
    assert!(
        (r / r_ref - 1.0).abs() < 0.1,
        "{side}^3: shock at {r}, reference {r_ref}"
    );
    assert!(
        s.energy_rel_drift.abs() < 1e-3,
        "{side}^3: energy drift {:e}",
        s.energy_rel_drift
    );
    assert!(
        s.momentum_rel_drift < momentum,
        "{side}^3: momentum drift {:e}",
        s.momentum_rel_drift
    );
    for k in 0..3 {
        assert!(
            l1[k] < L1_MAX[k],
            "{side}^3: L1 near the shock {l1:?} against bounds {L1_MAX:?}"
        );
        assert!(
            null[k] > L1_MAX[k],
            "{side}^3: the untouched state's L1 {null:?} passes the bounds {L1_MAX:?}"
        );
    }
}
