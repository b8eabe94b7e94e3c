//! Sedov-Taylor blast wave to t = 0.05 against the similarity solution, at
//! 20^3 and 30^3, with the case's scheme (`gas`).
//!
//! Measured (global steps from the case's first step, 2 threads,
//! 2026-12-07, evening): L1 rho / P / |v| 0.1166 / 0.2839 / 0.1177 at
//! 20^3, 0.0854 / 0.2268 / 0.0890 at 30^3; the shock radius of the
//! similarity solution whose enclosed mass is closest to the particles'
//! 0.3423 (-1.5%) and 0.3456 (-0.5%), exact 0.34747 (block steps: 0.3424 / 0.3454, and
//! 0.3471 at 40^3). The paper's
//! scheme (global steps from `--first-step criteria`): L1 0.1565 / 0.3423 /
//! 0.1932 and 0.1513 / 0.2735 / 0.1592, shock +3.8% and +3.0% (its gas
//! runs ahead of the shock).
//!
//! The L1 bounds at 30^3 are the C++ SPH-EXA's `ve` scheme's figures
//! there (0.111 / 0.266 / 0.126, issue 16, `docs/schemes.md`), an
//! independent code. The untouched initial state (rho = 1, the deposited
//! energy's pressure, at rest) scores L1 rho / P / |v| = 0.147 / 0.48 /
//! 0.24 against the t = 0.05 solution (computed in the test): it fails
//! each of them.

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
    // The front within 2% at both.
    for s in [&coarse, &fine] {
        let (r, l1) = (s.shock_radius.unwrap(), s.l1.unwrap());
        println!(
            "{} particles: shock {r:.4}, L1 rho / P / |v| {:.4} / {:.4} / {:.4}, energy drift {:.1e}",
            s.particles, l1.rho, l1.p, l1.v, s.energy_rel_drift
        );
        assert!(
            (r / r_ref - 1.0).abs() < 0.02,
            "{} particles: shock at {r}, reference {r_ref}",
            s.particles
        );
    }
    for s in [&coarse, &fine] {
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
    // The C++ `ve` scheme's L1 at 30^3, which the null solution fails.
    let bounds = [0.111, 0.266, 0.126];
    let null = null_solution(30);
    for (k, (name, l)) in [("rho", f.rho), ("P", f.p), ("|v|", f.v)]
        .into_iter()
        .enumerate()
    {
        assert!(
            l < bounds[k],
            "L1({name}) = {l} at 30^3, bound {}",
            bounds[k]
        );
        assert!(null[k] > bounds[k], "the initial state {null:?} would pass");
    }
}

/// Sedov to t = 0.05 with `--first-step criteria` (the global run's
/// cheapest start) under `time_steps`, at `side^3`, with the case's scheme
/// (`gas`) or the paper's.
fn run_stepped(side: usize, time_steps: sph_core::TimeSteps, paper: bool) -> Summary {
    let overrides = sph_apps::cases::SchemeOverrides {
        preset: paper.then_some(sph_core::Scheme::PAPER),
        first_step: Some(sph_core::timestep::FirstStep::Criteria),
        ..Default::default()
    };
    let mut scene = sph_validation::scene_with("sedov", side, &overrides);
    scene.config.time_steps = time_steps;
    let name = sph_core::Choice::name(&time_steps);
    let out = sph_validation::scratch(&format!("sedov{side}-{name}-{paper}"));
    sph_validation::run(scene, Stop::Time(T_END), &out)
}

/// The checks of block against global at one resolution: every L1 within
/// 3% of the global run's, the fitted shock radius within 0.005 (1.4%) of
/// the global run's, energy drift below
/// `energy`, momentum at round-off (the blast is symmetric), updates below
/// half. Returns the update ratio.
fn block_against_global(side: usize, paper: bool, energy: f64) -> f64 {
    use sph_core::TimeSteps;
    let global = run_stepped(side, TimeSteps::Global, paper);
    let block = run_stepped(side, TimeSteps::Block, paper);
    let (g, b) = (global.l1.unwrap(), block.l1.unwrap());
    for (name, lg, lb) in [("rho", g.rho, b.rho), ("P", g.p, b.p), ("|v|", g.v, b.v)] {
        assert!(
            lb <= 1.03 * lg,
            "{side}^3 (paper {paper}): L1({name}) {lb} under block steps, {lg} global: more than 3% above"
        );
    }
    let (r, r_global) = (block.shock_radius.unwrap(), global.shock_radius.unwrap());
    assert!(
        (r - r_global).abs() <= 0.005,
        "{side}^3: shock at {r}, global run {r_global}"
    );
    assert!(
        block.energy_rel_drift.abs() < energy,
        "{side}^3 (paper {paper}): energy drift {:e}",
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
/// from the same start, with the case's scheme (`gas`: viscosity switches
/// advanced over each particle's own step, generalised volumes predicted
/// with the density, conduction exchanged as impulses). Measured
/// (2026-12-07, evening): L1 rho / P / |v| 0.1154 / 0.2787 / 0.1141 at
/// 20^3 and 0.0833 / 0.2220 / 0.0861 at 30^3 (global 0.1166 / 0.2841 /
/// 0.1177 and 0.0854 / 0.2268 / 0.0890); energy drift -2.8e-4 at both
/// (global -3.0e-4, -1.2e-4; `best` 1.9e-4 at both, global -3.0e-4 and
/// -1.4e-4): the bound 5e-4 is above every global run's drift here, and far below
/// the -2.75e-3 of `gas` at 20^3 before its conduction was exchanged as
/// impulses; updates 0.35 and 0.26 of the global run's. The initial state
/// held still scores L1(P) 0.48 and L1(|v|) 0.24 (test above): far
/// outside 1.03 times the global run's.
#[test]
fn block_steps_match_the_global_run_with_a_fraction_of_its_updates() {
    let ratios =
        [(20, 5e-4), (30, 5e-4)].map(|(side, energy)| block_against_global(side, false, energy));
    // The cold gas's share grows with resolution: the saving too.
    assert!(ratios[1] < ratios[0], "update ratios {ratios:?}");
}

/// The same with the paper's scheme (constant alpha = 1, grad-h, m / rho
/// volumes). Measured (2026-12-04): updates 177,496 of 440,000 (0.40) and
/// 647,848 of 2,160,000 (0.30); L1 rho / P / |v| 0.1517 / 0.3378 / 0.1859
/// against 0.1565 / 0.3423 / 0.1932 at 20^3, 0.1483 / 0.2733 / 0.1471
/// against 0.1513 / 0.2735 / 0.1592 at 30^3; energy drift 7.0e-4 and
/// -2.8e-4 (global 9.7e-5, 2.3e-4); momentum drift 7e-18 and 5e-18.
#[test]
fn block_steps_match_the_global_run_with_the_papers_scheme() {
    for side in [20, 30] {
        block_against_global(side, true, 1e-3);
    }
}
