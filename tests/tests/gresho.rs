//! The Gresho-Chan vortex (R1 = 0.2, rho = 1, P0 = 5, gamma = 5/3) in a
//! thin periodic slab, 24 x 24 x 8 particles, to t = 1. The exact solution
//! is the initial state; the error is L1(v_phi) over cylindrical radii up
//! to 0.5.
//!
//! Two schemes: the paper's (constant alpha = 1, this case's default
//! before issue 42) and the default, `gas` (viscosity switches with AV
//! cleaning, conduction). Measured earlier (2 threads), L1(v_phi) with the
//! paper's scheme / the paper's with viscosity switches: 0.175 / 0.104 at
//! 24^2, 0.150 / 0.100 at 32^2. Bounds: those 24^2 figures plus 20%, the
//! second for the default, which must also beat the paper's. Measured
//! 2026-12-07, evening: `paper` 0.1753, `gas` 0.0873 (turn errors 0.126
//! / 0.092); block steps 0.1767 / 0.0898 (0.123 / 0.097). Null
//! solution: the vortex decayed to rest has L1(v_phi) = 0.32 (computed in
//! the test from the particles), above both bounds.

use sph_apps::cases::{gresho, Reference, SchemeOverrides};
use sph_apps::reference::Gresho;
use sph_apps::simulation::Stop;
use sph_apps::Summary;
use sph_core::{Particles, Scheme};

const SIDE: usize = 24;
const T_END: f64 = 1.0;
const BOUND_PAPER: f64 = 0.21;
const BOUND_DEFAULT: f64 = 0.125;
/// Bounds on the mean distance from where the exact flow carries each
/// particle (r0 < 0.4): the paper's scheme, the default.
const TURN_BOUND_PAPER: f64 = 0.14;
const TURN_BOUND_DEFAULT: f64 = 0.125;

/// Mean distance, over the particles starting at cylindrical radius below
/// 0.4, between position `k` of `(x, y)` (particle `id[k]`) and where the
/// exact vortex carries that particle from its start in `p0` by `T_END`.
fn turn_error(p0: &Particles, id: &[f64], x: &[f64], y: &[f64]) -> f64 {
    let vortex = Gresho::standard(gresho::GAMMA).expect("the standard vortex");
    let (mut sum, mut n) = (0.0, 0usize);
    for k in 0..id.len() {
        let i = id[k] as usize;
        assert_eq!(p0.id[i], i as u64);
        let (x0, y0) = (p0.x[i], p0.y[i]);
        let r0 = x0.hypot(y0);
        if r0 >= 0.4 {
            continue;
        }
        let angle = vortex.v_phi(r0) * T_END / r0;
        let (c, s) = (angle.cos(), angle.sin());
        sum += (x[k] - (c * x0 - s * y0)).hypot(y[k] - (s * x0 + c * y0));
        n += 1;
    }
    sum / n as f64
}

/// The summary and the [`turn_error`] of a run with the paper's scheme
/// or (`paper` false) the case's default.
fn run(paper: bool, name: &str) -> (Summary, f64) {
    run_stepped(paper, name, sph_core::TimeSteps::Global)
}

/// [`run`] with `time_steps`.
fn run_stepped(paper: bool, name: &str, time_steps: sph_core::TimeSteps) -> (Summary, f64) {
    let overrides = SchemeOverrides {
        preset: paper.then_some(Scheme::PAPER),
        ..Default::default()
    };
    let mut scene = sph_validation::scene_with("gresho", SIDE, &overrides);
    scene.config.time_steps = time_steps;
    let p0 = scene.particles.clone();
    let out = sph_validation::scratch(name);
    let summary = sph_validation::run_writing_particles(scene, Stop::Time(T_END), &out);
    let q = sph_validation::read_particles(&out);
    (summary, turn_error(&p0, &q["id"], &q["x"], &q["y"]))
}

#[test]
fn gresho_vortex_keeps_its_rotation_better_with_the_default_scheme() {
    // Null solution: everything at rest.
    let scene = sph_validation::scene("gresho", SIDE);
    let Some(reference @ Reference::Vortex(_)) = scene.reference.clone() else {
        panic!("gresho has a vortex reference");
    };
    let p = &scene.particles;
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..p.len() {
        let r = reference.coordinate([p.x[i], p.y[i], p.z[i]]);
        if reference.covers(r) {
            sum += reference.state(r, T_END).v.abs();
            n += 1;
        }
    }
    let at_rest = sum / n as f64;
    assert!(at_rest > 1.5 * BOUND_PAPER, "rest gives {at_rest}");
    // A frozen state: every particle where it started.
    let ids: Vec<f64> = (0..p.len()).map(|i| i as f64).collect();
    let frozen = turn_error(p, &ids, &p.x, &p.y);
    assert!(
        frozen > 2.0 * TURN_BOUND_PAPER.max(TURN_BOUND_DEFAULT),
        "a frozen state's turn error {frozen} is within twice the bounds"
    );

    let (paper, turn_paper) = run(true, "gresho24-paper");
    let (default, turn_default) = run(false, "gresho24-default");
    println!("turn error: paper {turn_paper}, default {turn_default}, frozen {frozen}");
    assert!(
        turn_paper < TURN_BOUND_PAPER,
        "paper: the vortex turned with a mean error of {turn_paper}"
    );
    assert!(
        turn_default < TURN_BOUND_DEFAULT,
        "default: the vortex turned with a mean error of {turn_default}"
    );
    bounds_hold(&paper, &default, 1e-12);
}

/// L1(v_phi) of both runs within their bounds, the default's lower, energy
/// to 1e-3 and momentum to `momentum`.
fn bounds_hold(paper: &Summary, default: &Summary, momentum: f64) {
    let (a, s) = (paper.l1.unwrap().v, default.l1.unwrap().v);
    println!("L1(v_phi): paper {a}, default {s}");
    assert!(a < BOUND_PAPER, "paper: L1(v_phi) {a}");
    assert!(s < BOUND_DEFAULT, "default: L1(v_phi) {s}");
    assert!(s < a, "default {s} not below the paper's {a}");
    for run in [paper, default] {
        assert!(
            run.energy_rel_drift.abs() < 1e-3,
            "{}",
            run.energy_rel_drift
        );
        assert!(
            run.momentum_rel_drift < momentum,
            "{}",
            run.momentum_rel_drift
        );
    }
}

/// The same bounds under block time steps (issue 41). The vortex has
/// nearly one time step everywhere: where one step a hair below the
/// smallest criterion step for every particle costs fewer updates than
/// the power-of-two bins of the run's span, that is the step (the bins
/// alone cost 1.57x the global run's updates). Measured (2026-12-05,
/// alpha = 1 and the paper's scheme with switches, the test's pair then):
/// 648 / 764 sub-steps, 0.98x / 0.99x the global run's updates
/// (alpha = 1 / switches), L1(v_phi) 0.1697 / 0.1117 (global 0.1753 /
/// 0.1045), turn errors 0.124 / 0.117, energy drift 2.6e-6 / 7.2e-5,
/// momentum 2.6e-16 / 6.9e-6; with switches at side 32 momentum 1.1e-5
/// (a pair's forces at different times where the switches' particles sit
/// in two bins): bound 1e-4, the block bound of the other cases.
#[test]
fn gresho_vortex_holds_its_bounds_under_block_time_steps() {
    let block = sph_core::TimeSteps::Block;
    let (paper, turn_paper) = run_stepped(true, "gresho24-paper-block", block);
    let (default, turn_default) = run_stepped(false, "gresho24-default-block", block);
    println!("block: turn error paper {turn_paper}, default {turn_default}");
    assert!(turn_paper < TURN_BOUND_PAPER, "{turn_paper}");
    assert!(turn_default < TURN_BOUND_DEFAULT, "{turn_default}");
    bounds_hold(&paper, &default, 1e-4);
}
