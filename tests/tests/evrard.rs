//! Evrard collapse (the unit sphere cut from a glass, self-gravity) to
//! t = 2.0 with the case's scheme (`gas`, issue 42's one scheme for the
//! ideal-gas cases), Courant factor and time steps (block, the command
//! line's default), against the energies of the 1-D Lagrangian reference
//! in `docs/cases.md` (quoted there as good to 2%;
//! `tests/reference/evrard_1d.py`, an independent 1-D code, lands within
//! 0.8% of them). Issue 42's bounds (issue 16's, re-scoped): E_kin, E_int
//! and E_grav within 5% at t = 0.8 (infall) and t = 1.0 (the bounce); at
//! t = 2.0 E_int and E_grav within 5% and E_kin within 12% (it lives in
//! the ejected outer ~5% of the mass, which the 1-D code itself resolves
//! within 5% only with ~400 shells) and its error falling with
//! resolution (measured below, not asserted: the second resolution is
//! too long for CI); total energy (including E_grav) conserved to 1e-2 through the bounce
//! (t <= 1.5).
//!
//! Measured (2026-12-07, evening, release, 2 threads), 14,175 particles
//! (`-n 30`): t = 0.8 -0.3 / -1.3 / -1.0%, t = 1.0 +3.6 / -3.8 / -2.1%,
//! t = 2.0 -9.6 / +3.6 / +0.2%, drift through the bounce 2.6e-3 (9.9 M
//! updates). At 65,484 particles (`-n 50`, not run here: 18 minutes on 2
//! cores; `docs/schemes.md`, 2026-12-07 night): -0.2 / -1.5 / -1.4%,
//! +5.9 / -4.0 / -2.0%, -10.4 / -5.8 / -4.2%: E_kin at t = 1.0 and E_int
//! at t = 2.0 are outside their 5% there, and E_kin at t = 2.0 does not
//! fall with resolution (-9.6% at 14k); Courant 0.2 moves them by at
//! most 0.2 points (2026-12-08).

use sph_apps::simulation::Stop;
use sph_apps::Summary;
use std::path::Path;

/// E_kin, E_int and E_grav of run `s` (`label`) within `bound(t, name)`
/// (relative) of the reference at each of `times`.
fn energies_match(s: &Summary, times: &[f64], bound: impl Fn(f64, &str) -> f64, label: &str) {
    for &t in times {
        let e = s
            .energies
            .iter()
            .find(|e| (e.t - t).abs() < 1e-12)
            .unwrap_or_else(|| panic!("{label}: no energies at t = {t}"));
        for (name, got, want) in [
            ("E_kin", e.e_kin, e.e_kin_ref),
            ("E_int", e.e_int, e.e_int_ref),
            ("E_grav", e.e_grav, e.e_grav_ref),
        ] {
            let rel = (got - want) / want;
            println!(
                "{label}: t = {t}: {name} {got:.4} vs {want:.4} ({:+.1}%)",
                100.0 * rel
            );
            assert!(
                rel.abs() < bound(t, name),
                "{label}, t = {t}: {name} = {got}, reference {want}"
            );
        }
    }
}

/// Issue 42's bounds: 5% everywhere but E_kin at t = 2.0, 12%.
fn issue_bound(t: f64, name: &str) -> f64 {
    if (t - 2.0).abs() < 1e-12 && name == "E_kin" {
        0.12
    } else {
        0.05
    }
}

/// The largest |E_tot - E_tot(0)| / |E_tot(0)| through t = 1.5, from
/// `conserved.csv` in `out`.
fn drift_through_bounce(out: &Path) -> f64 {
    let text = std::fs::read_to_string(out.join("conserved.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ct, ce) = (col("t"), col("E_tot"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let e0 = rows[0][ce];
    rows.iter()
        .filter(|r| r[ct] <= 1.5)
        .map(|r| ((r[ce] - e0) / e0).abs())
        .fold(0.0, f64::max)
}

/// The case as a user runs it (`-n 30`, block time steps) to t = 2.0:
/// the energies within [`issue_bound`] and the drift through the bounce
/// within 1e-2.
#[test]
fn evrard_30_energies_match_reference() {
    let mut scene = sph_validation::scene("evrard", 30);
    scene.config.time_steps = sph_core::TimeSteps::Block;
    let out = sph_validation::scratch("evrard30");
    let s = sph_validation::run(scene, Stop::Time(2.0), &out);
    energies_match(&s, &[0.8, 1.0, 2.0], issue_bound, "30");
    let drift = drift_through_bounce(&out);
    println!("largest |E_tot drift| through t = 1.5: {drift:.2e}");
    assert!(drift < 1e-2, "energy drift {drift:e}");
}

/// Block time steps with self-gravity (issue 41): Evrard to t = 1.0 at
/// `-n 24` and `-n 32` (17,143 particles), the case's scheme. Gravity is
/// evaluated for the active particles' groups only, on the tree of the
/// last domain sync with its cells widened by the drift since. Energies
/// within 5% of the reference at t = 0.8 and 1.0 (the issue's bound),
/// total energy of the end state (every particle fresh) within 1e-2 of
/// the start (the global test's bound through the bounce), and fewer than
/// 60% of the particles updated per sub-step on average. Measured
/// (2026-12-07, evening, `gas` at Courant 0.3): at 32 t = 0.8 -0.3 /
/// -1.5 / -1.4%, t = 1.0 +4.4 / -3.9 / -2.0%, drift -2.7e-3, 4.47 M
/// updates in 818 sub-steps (0.32 per sub-step); at 24 -0.5 / -1.1 /
/// -1.2% and +1.1 / -3.9 / -2.4%, drift -1.1e-3, 1.65 M updates in 718
/// sub-steps (0.32). With the `evrard` preset at Courant 0.5 (2026-12-06,
/// night): at 32 -2.0 / +0.7 / -1.3%, +2.4 / -1.4 / -0.6%, drift
/// -3.8e-3; at 24 -3.6 / +0.7 / -1.9%, -0.1 / -3.1 / -1.9%, drift
/// -6.7e-3. The drift bound was 5e-3 while the conduction was a rate
/// (drift -3.4e-3 at 32, -3.1e-3 at 24): the impulses conserve their own
/// exchange to round-off but move `u` of particles inside their step,
/// whose held pressure work then lags (an inactive particle's held
/// gravity and `du` lag its active neighbours', so pair terms are not
/// equal and opposite within a sync; `docs/block-timesteps.md`).
#[test]
fn evrard_block_steps_energies_match_reference() {
    for side in [24, 32] {
        let mut scene = sph_validation::scene("evrard", side);
        scene.config.time_steps = sph_core::TimeSteps::Block;
        let out = sph_validation::scratch(&format!("evrard{side}-block"));
        let s = sph_validation::run(scene, Stop::Time(1.0), &out);
        energies_match(&s, &[0.8, 1.0], |_, _| 0.05, &side.to_string());
        println!(
            "{side}: drift {:.2e}, {} updates in {} sub-steps of {} particles",
            s.energy_rel_drift, s.particle_updates, s.steps, s.particles
        );
        assert!(
            s.energy_rel_drift.abs() < 1e-2,
            "{side}: energy drift {:e}",
            s.energy_rel_drift
        );
        let per_substep = s.particle_updates as f64 / (s.steps * s.particles as u64) as f64;
        assert!(
            per_substep < 0.6,
            "{side}: {per_substep} of the particles per sub-step"
        );
    }
}
