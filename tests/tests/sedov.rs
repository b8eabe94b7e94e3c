//! Sedov-Taylor blast wave to t = 0.05 against the similarity solution, at
//! 20^3 and 30^3, with the case's scheme (the paper's).
//!
//! Measured (2 threads): L1 rho / P / |v| 0.1563 / 0.3423 / 0.1931 at 20^3,
//! 0.1510 / 0.2733 / 0.1591 at 30^3 (0.134 / 0.224 / 0.131 at 40^3); the
//! densest radial bin at 0.3425 at both (bins are 0.005 wide; exact shock
//! 0.34747, -1.4%).
//!
//! Null solution: the untouched initial state (rho = 1, the deposited
//! energy's pressure, at rest) scores L1 rho / P / |v| = 0.147 / 0.48 /
//! 0.24 against the t = 0.05 solution (computed in the test). Its L1(rho)
//! is below the one SPH reaches at these resolutions (the smoothed shell
//! costs as much as the flat field), so no L1(rho) bound could tell them
//! apart: rho is checked by convergence (lower at 30^3 than at 20^3) and by
//! the peak density, P and |v| by bounds (30^3 figures + 10%) that the null
//! solution fails, and all three by convergence.

use sph_apps::simulation::Stop;
use sph_apps::Summary;

const T_END: f64 = 0.05;

fn run(side: usize) -> Summary {
    let scene = sph_validation::scene("sedov", side);
    let out = sph_validation::scratch(&format!("sedov{side}"));
    sph_validation::run(scene, Stop::Time(T_END), &out)
}

/// L1 rho / P / |v| of the initial state of `side^3`, held still.
fn null_solution(side: usize) -> [f64; 3] {
    let scene = sph_validation::scene("sedov", side);
    let reference = scene.reference.clone().unwrap();
    let p = &scene.particles;
    let gamma = sph_apps::cases::sedov::GAMMA;
    let n = p.len() as f64;
    let mut l1 = [0.0; 3];
    for i in 0..p.len() {
        let r = reference.coordinate([p.x[i], p.y[i], p.z[i]]);
        let s = reference.state(r, T_END);
        l1[0] += (1.0 - s.rho).abs() / n;
        l1[1] += ((gamma - 1.0) * p.u[i] - s.p).abs() / n;
        l1[2] += s.v.abs() / n;
    }
    l1
}

#[test]
fn sedov_converges_to_the_similarity_solution() {
    let coarse = run(20);
    let fine = run(30);
    let r_ref = fine.shock_radius_ref.unwrap();
    // Reference value of VALIDATION.md, computed independently.
    assert!(
        (r_ref - 0.3475).abs() < 1e-3,
        "reference shock radius {r_ref}"
    );
    for s in [&coarse, &fine] {
        let r = s.shock_radius.unwrap();
        assert!(
            (r / r_ref - 1.0).abs() < 0.02,
            "{} particles: shock at {r}, reference {r_ref}",
            s.particles
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
    // SPH smooths the jump: the peak stays below the strong-shock limit 4,
    // and sharpens with resolution.
    assert!(
        fine.peak_density < 4.0,
        "peak density {}",
        fine.peak_density
    );
    assert!(
        fine.peak_density > coarse.peak_density && fine.peak_density > 1.8,
        "peak density {} (20^3: {})",
        fine.peak_density,
        coarse.peak_density
    );

    let (c, f) = (coarse.l1.unwrap(), fine.l1.unwrap());
    for (name, a, b) in [("rho", c.rho, f.rho), ("P", c.p, f.p), ("|v|", c.v, f.v)] {
        assert!(b < a, "L1({name}) does not fall: {a} at 20^3, {b} at 30^3");
    }
    let bounds = [0.30, 0.18];
    assert!(f.p < bounds[0], "L1(P) = {}", f.p);
    assert!(f.v < bounds[1], "L1(|v|) = {}", f.v);
    let null = null_solution(30);
    assert!(
        null[1] > bounds[0] && null[2] > bounds[1],
        "the initial state {null:?} would pass"
    );
}

/// Sedov to t = 0.05 with `--first-step criteria` (the global run's
/// cheapest start) under `time_steps`, at `side^3`, with the case's scheme
/// or `best`.
fn run_stepped(side: usize, time_steps: sph_core::TimeSteps, best: bool) -> Summary {
    let overrides = sph_apps::cases::SchemeOverrides {
        preset: best.then_some(sph_core::Scheme::BEST),
        first_step: Some(sph_core::timestep::FirstStep::Criteria),
        ..Default::default()
    };
    let mut scene = sph_validation::scene_with("sedov", side, &overrides);
    scene.config.time_steps = time_steps;
    let name = sph_core::Choice::name(&time_steps);
    let out = sph_validation::scratch(&format!("sedov{side}-{name}-{best}"));
    sph_validation::run(scene, Stop::Time(T_END), &out)
}

/// The checks of block against global at one resolution: every L1 within
/// 3% of the global run's, the shock within one radial bin of the global
/// run's (both within 2% of the exact radius for `paper`, 4.3% inside it
/// for `best` at 20^3), energy drift below
/// `energy`, momentum at round-off (the blast is symmetric), updates below
/// half. Returns the update ratio.
fn block_against_global(side: usize, best: bool, energy: f64) -> f64 {
    use sph_core::TimeSteps;
    let global = run_stepped(side, TimeSteps::Global, best);
    let block = run_stepped(side, TimeSteps::Block, best);
    let (g, b) = (global.l1.unwrap(), block.l1.unwrap());
    for (name, lg, lb) in [("rho", g.rho, b.rho), ("P", g.p, b.p), ("|v|", g.v, b.v)] {
        assert!(
            lb <= 1.03 * lg,
            "{side}^3 (best {best}): L1({name}) {lb} under block steps, {lg} global: more than 3% above"
        );
    }
    // The densest radial bin (0.005 wide) where the global run has it.
    let (r, r_global) = (block.shock_radius.unwrap(), global.shock_radius.unwrap());
    assert!(
        (r - r_global).abs() <= 0.0051,
        "{side}^3: shock at {r}, global run {r_global}"
    );
    assert!(
        block.energy_rel_drift.abs() < energy,
        "{side}^3 (best {best}): energy drift {:e}",
        block.energy_rel_drift
    );
    assert!(
        block.momentum_rel_drift < 1e-12,
        "{side}^3: momentum drift {:e}",
        block.momentum_rel_drift
    );
    assert_eq!(
        global.particle_updates,
        global.steps * global.particles as u64
    );
    let ratio = block.particle_updates as f64 / global.particle_updates as f64;
    assert!(
        ratio < 0.5,
        "{side}^3: block updates {ratio} of the global run's"
    );
    ratio
}

/// Block time steps (issue 41) at 20^3 and 30^3 against the global run
/// from the same start. Measured (2026-12-04): updates 177,496 of 440,000
/// (0.40) and 647,848 of 2,160,000 (0.30); L1 rho / P / |v| 0.1517 /
/// 0.3378 / 0.1859 against 0.1565 / 0.3423 / 0.1932 at 20^3, 0.1483 /
/// 0.2733 / 0.1471 against 0.1513 / 0.2735 / 0.1592 at 30^3; energy drift
/// 7.0e-4 and -2.8e-4 (global 9.7e-5, 2.3e-4); momentum drift 7e-18 and
/// 5e-18 (the blast is symmetric: the bound of the global runs holds).
/// The initial state held still scores L1(P) 0.48 and L1(|v|) 0.24
/// (test above): far outside 1.03 times the global run's.
#[test]
fn block_steps_match_the_global_run_with_a_fraction_of_its_updates() {
    let ratios = [20, 30].map(|side| block_against_global(side, false, 1e-3));
    // The cold gas's share grows with resolution: the saving too.
    assert!(ratios[1] < ratios[0], "update ratios {ratios:?}");
}

/// The same with `best` (viscosity switches advanced over each particle's
/// own step, generalised volumes predicted with the density, conduction).
/// Measured (2026-12-04): L1 rho / P / |v| 0.1127 / 0.2605 / 0.1119 at
/// 20^3 and 0.0855 / 0.2169 / 0.0862 at 30^3 (global 0.0871 / 0.2188 /
/// 0.0887 at 30^3); energy drift -1.45e-3 and -4.6e-4 (global -3.0e-4,
/// -1.4e-4): the 20^3 run is outside the paper scheme's 1e-3, so the bound
/// here is 2e-3 (40^3: 2.9e-4); updates 0.31 of the global run's at 30^3
/// (0.255 at 40^3).
#[test]
fn block_steps_with_switches_and_volume_elements_match_the_global_run() {
    for side in [20, 30] {
        block_against_global(side, true, 2e-3);
    }
}
