//! Driven subsonic turbulence (`turbulence`: isothermal gas, c = 1, in the
//! periodic unit box, stirred as SPH-EXA stirs it, Federrath et al. 2010)
//! at 16^3 to t = 10, six turnover times `T = 1 / (2 * 0.3)`:
//!
//! - **Rise**: the mass-weighted rms Mach number reaches half the target,
//!   0.15, by t = T. Measured 0.222 / 0.238 / 0.234 (seeds 251299, 2, 3).
//!   The same glass left undriven (`--stir off`) moves only by its own
//!   noise: 0.028 at t = T; it fails this check, and the test runs it.
//! - **Saturation**: the means over [3T, 4.5T] and [4.5T, 6T] within 15%
//!   of each other. Measured 11%, 1% and 1% for the three seeds.
//! - **Level**: the mean over [3T, 6T] within 25% of the target 0.3 at
//!   16^3. Measured 0.244 / 0.246 / 0.255: SPH at 16^3 dissipates more
//!   than the driving's open-loop calibration assumes; the 10%
//!   is the target at 32^3 and 64^3, where `docs/cases.md` gives the
//!   figures (the 32^3 run is the ignored test below).
//! - **Energy**: the scheme conserves `E - W` (W the stirring's work,
//!   `W_ext` in `conserved.csv`): `|E - E_0 - W| / W` below 1e-2 at
//!   t = 10. Measured 2.2e-3 / 2.5e-3 / 2.3e-3 (it depends on the Courant
//!   factor: 1.3% by t = 4 at 0.3, see the case's docs). The work itself
//!   is checked against the analytic work of a frozen field in
//!   `sph-core/tests/stirred.rs`.
//! - **Momentum**: the driving's mean is removed with exact sums, so the
//!   net momentum stays at round-off: below 1e-13 of `M * 0.3 * c`
//!   (measured ~1e-17).

use sph_apps::cases::{turbulence, SchemeOverrides};
use sph_apps::simulation::Stop;
use std::path::Path;

/// The turnover time `L / (2 v)`.
const T: f64 = 1.0 / (2.0 * turbulence::MACH_TARGET);

/// `(t, mach_rms)` of every step of `curve.csv` in `dir`.
fn mach_curve(dir: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(dir.join("curve.csv")).expect("curve.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let (t, m) = (
        header.iter().position(|h| *h == "t").expect("t"),
        header
            .iter()
            .position(|h| *h == "mach_rms")
            .expect("mach_rms"),
    );
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            (v[t], v[m])
        })
        .collect()
}

/// The first Mach number at or after `t`.
fn mach_at(curve: &[(f64, f64)], t: f64) -> f64 {
    curve.iter().find(|c| c.0 >= t).expect("reached t").1
}

/// The mean Mach number over the steps in `[a, b)`.
fn mean_mach(curve: &[(f64, f64)], a: f64, b: f64) -> f64 {
    let v: Vec<f64> = curve
        .iter()
        .filter(|c| (a..b).contains(&c.0))
        .map(|c| c.1)
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The first and last rows of `conserved.csv` in `dir` as
/// `(E_tot, W_ext, [px, py, pz])`.
fn energies(dir: &Path) -> [(f64, f64, [f64; 3]); 2] {
    let text = std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).expect(n);
    let row = |l: &str| {
        let v: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
        (
            v[col("E_tot")],
            v[col("W_ext")],
            [v[col("px")], v[col("py")], v[col("pz")]],
        )
    };
    let rows: Vec<&str> = lines.collect();
    [row(rows[0]), row(rows[rows.len() - 1])]
}

/// The driven run rises, saturates near the target, and conserves E - W
/// and momentum; the undriven one does not rise.
#[test]
fn driven_turbulence_rises_and_saturates() {
    let out = sph_validation::scratch("turbulence-16");
    let scene = sph_validation::scene("turbulence", 16);
    let mass = scene.particles.m.iter().sum::<f64>();
    sph_validation::run(scene, Stop::Time(6.0 * T), &out);
    let curve = mach_curve(&out);
    let target = turbulence::MACH_TARGET;

    let rise = mach_at(&curve, T);
    let (early, late) = (
        mean_mach(&curve, 3.0 * T, 4.5 * T),
        mean_mach(&curve, 4.5 * T, 6.0 * T),
    );
    let level = mean_mach(&curve, 3.0 * T, 6.0 * T);
    println!("16^3: M(T) {rise:.3}, means {early:.3} / {late:.3}, over [3T, 6T] {level:.3}");
    assert!(
        rise > 0.5 * target,
        "M(T) = {rise}: no rise to half the target"
    );
    assert!(
        (early / late - 1.0).abs() < 0.15,
        "not saturated: {early} then {late}"
    );
    assert!(
        (level / target - 1.0).abs() < 0.25,
        "level {level} against {target}"
    );

    let [(e0, w0, _), (e, w, p)] = energies(&out);
    let closure = (e - e0 - (w - w0)).abs() / (w - w0);
    println!("16^3: E - E0 - W = {closure:.2e} of W = {w:.4}");
    assert!(closure < 1e-2, "E - E0 - W = {closure} of W");
    let p_rel = p.iter().fold(0.0f64, |m, c| m.max(c.abs())) / (mass * target);
    assert!(p_rel < 1e-13, "net momentum {p:?}: {p_rel:e} of M v");

    // The same glass, not driven: the rise check fails.
    let off = sph_validation::scratch("turbulence-16-undriven");
    let undriven = SchemeOverrides {
        stirring: Some(None),
        ..Default::default()
    };
    let scene = sph_validation::scene_with("turbulence", 16, &undriven);
    assert!(scene.config.stirring.is_none());
    sph_validation::run(scene, Stop::Time(1.01 * T), &off);
    let still = mach_at(&mach_curve(&off), T);
    println!("16^3 undriven: M(T) {still:.3}");
    assert!(still < 0.5 * target, "undriven M(T) = {still}");
}

/// 32^3 to six turnover times: the mean Mach number over [3T, 6T] within
/// 10% of the target (the bound; about 6 minutes on 2 cores, run
/// for the docs with `--ignored`).
#[test]
#[ignore]
fn at_32_the_mach_number_is_within_10_percent_of_the_target() {
    let out = sph_validation::scratch("turbulence-32");
    sph_validation::run(
        sph_validation::scene("turbulence", 32),
        Stop::Time(6.0 * T),
        &out,
    );
    let curve = mach_curve(&out);
    let level = mean_mach(&curve, 3.0 * T, 6.0 * T);
    println!("32^3: mean M over [3T, 6T] {level:.3}");
    assert!(
        (level / turbulence::MACH_TARGET - 1.0).abs() < 0.1,
        "level {level}"
    );
}
