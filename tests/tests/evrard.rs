//! Evrard collapse (the unit sphere cut from a glass at 30 particles per
//! 2 units: 14175 particles, self-gravity) to t = 2.0, with the case's
//! scheme and Courant factor, against the energies of the 1-D Lagrangian
//! reference in `docs/cases.md` (quoted there as good to 2%;
//! `tests/reference/evrard_1d.py`, an independent 1-D code, lands within
//! 0.8% of them): E_kin, E_int and E_grav within 7.5% at t = 0.8 (infall),
//! t = 1.0 (the bounce) and t = 2.0 (after it); total energy (including
//! E_grav) conserved to 1e-2 through the bounce (t <= 1.5).
//!
//! Measured: t = 0.8 -3.0% / +0.6% / -0.7%, t = 1.0 -0.0% / -2.1% /
//! -1.4%, t = 2.0 -4.3% / +5.1% / +1.7%, drift 7.1e-4 (962 steps, ~2
//! minutes on 2 cores); at 40^3 every entry is within 4.7% (and at 20^3
//! within 6.5%, measured with the earlier Courant factor 0.4), so 7.5% is the reference's 2% above the spread over resolutions. E_kin at
//! t = 1.0 falls by 2 per unit time there: 7.5% of it is a shift of the
//! bounce by 0.01 in time.

use sph_apps::simulation::Stop;
use sph_apps::Summary;

/// E_kin, E_int and E_grav of run `s` (`label`) within `bound` (relative)
/// of the reference at each of `times`.
fn energies_match(s: &Summary, times: &[f64], bound: f64, label: &str) {
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
                rel.abs() < bound,
                "{label}, t = {t}: {name} = {got}, reference {want}"
            );
        }
    }
}

#[test]
fn evrard_30_energies_match_reference() {
    let scene = sph_validation::scene("evrard", 30);
    let out = sph_validation::scratch("evrard30");
    let s = sph_validation::run(scene, Stop::Time(2.0), &out);

    energies_match(&s, &[0.8, 1.0, 2.0], 0.075, "30");

    // Total energy through the bounce, from conserved.csv.
    let text = std::fs::read_to_string(out.join("conserved.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ct, ce) = (col("t"), col("E_tot"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let e0 = rows[0][ce];
    let drift = rows
        .iter()
        .filter(|r| r[ct] <= 1.5)
        .map(|r| ((r[ce] - e0) / e0).abs())
        .fold(0.0, f64::max);
    println!("largest |E_tot drift| through t = 1.5: {drift:.2e}");
    assert!(drift < 1e-2, "energy drift {drift:e}");
}

/// Block time steps with self-gravity (issue 41): Evrard to t = 1.0 at
/// `-n 24` and `-n 32` (17,143 particles), the case's scheme. Gravity is
/// evaluated for the active particles' groups only, on the tree of the
/// last domain sync with its cells widened by the drift since. Energies
/// within 5% of the reference at t = 0.8 and 1.0 (the bound),
/// total energy of the end state (every particle fresh) within 1e-2 of
/// the start (the global test's bound through the bounce), and fewer than
/// 60% of the particles updated per sub-step on average. Measured
/// (2026-12-06, night, the conduction exchanged as impulses): at 32
/// t = 0.8 -2.0% / +0.7% / -1.3%, t = 1.0 +2.4% / -1.4% / -0.6% (global
/// -2.6 / +0.6 / -0.6 and +0.7 / -1.8 / -1.2), drift -3.8e-3 (global
/// 3.1e-4), 2.83 M updates; at 24 -3.6 / +0.7 / -1.9% and -0.1 / -3.1 /
/// -1.9%, drift -6.7e-3, 1.13 M updates in 532 sub-steps (0.29 per
/// sub-step). The drift bound was 5e-3 while the conduction was a rate
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
        energies_match(&s, &[0.8, 1.0], 0.05, &side.to_string());
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
