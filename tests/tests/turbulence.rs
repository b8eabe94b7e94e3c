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
//!   factor: 1.3% by t = 4 at 0.3, see the case's docs).
//! - **Input**: the work W itself against the driving's analytic input,
//!   the free-particle work of its own random field path, while the gas
//!   has not yet moved through the field (below); a frozen field's
//!   `t^2 / 2 sum m |a|^2` is checked in `sph-core/tests/integration/stirred.rs`.
//! - **Momentum**: the driving's mean is removed with exact sums, so the
//!   net momentum stays at round-off: below 1e-13 of `M * 0.3 * c`
//!   (measured ~1e-17).

use sph_apps::cases::{turbulence, SchemeOverrides};
use sph_apps::simulation::Stop;
use sph_core::stirring::{StirParams, Stirring};
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

/// The statistics and conservation checks of a driven run in `out` of
/// gas of mass `mass`, at 16^3 (`label` names the run): rise, saturation,
/// level, `E - W`, and the net momentum within `momentum` of `M v`.
fn driven_checks(out: &Path, mass: f64, momentum: f64, label: &str) {
    let curve = mach_curve(out);
    let target = turbulence::MACH_TARGET;

    let rise = mach_at(&curve, T);
    let (early, late) = (
        mean_mach(&curve, 3.0 * T, 4.5 * T),
        mean_mach(&curve, 4.5 * T, 6.0 * T),
    );
    let level = mean_mach(&curve, 3.0 * T, 6.0 * T);
    println!("{label}: M(T) {rise:.3}, means {early:.3} / {late:.3}, over [3T, 6T] {level:.3}");
    assert!(
        rise > 0.5 * target,
        "{label}: M(T) = {rise}: no rise to half the target"
    );
    assert!(
        (early / late - 1.0).abs() < 0.15,
        "{label}: not saturated: {early} then {late}"
    );
    assert!(
        (level / target - 1.0).abs() < 0.25,
        "{label}: level {level} against {target}"
    );

    let [(e0, w0, _), (e, w, p)] = energies(out);
    let closure = (e - e0 - (w - w0)).abs() / (w - w0);
    println!("{label}: E - E0 - W = {closure:.2e} of W = {w:.4}");
    assert!(closure < 1e-2, "{label}: E - E0 - W = {closure} of W");
    let p_rel = p.iter().fold(0.0f64, |m, c| m.max(c.abs())) / (mass * target);
    println!("{label}: net momentum {p_rel:.2e} of M v");
    assert!(
        p_rel < momentum,
        "{label}: net momentum {p:?}: {p_rel:e} of M v"
    );
}

/// The driven run rises, saturates near the target, and conserves E - W
/// and momentum; the undriven one does not rise.
#[test]
fn driven_turbulence_rises_and_saturates() {
    let out = sph_validation::scratch("turbulence-16");
    let scene = sph_validation::scene("turbulence", 16);
    let mass = scene.particles.m.iter().sum::<f64>();
    sph_validation::run(scene, Stop::Time(6.0 * T), &out);
    driven_checks(&out, mass, 1e-13, "16^3");
    let target = turbulence::MACH_TARGET;

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

/// The same under block time steps (issue 41): the statistics and `E - W`
/// at the same bounds. The driving's net force is removed over the kept
/// accelerations of all particles, but a kick over a particle's own step
/// weights its accelerations by that step, so neither the driving nor
/// the pair forces conserve momentum to round-off here; the bound is
/// stated from two resolutions, with the limiter. Measured (2026-12-05):
/// 16^3 M(T) 0.224, means 0.258 / 0.246, level 0.252, E - E0 - W 4.6e-3
/// of W, momentum 1.0e-4 of M v (global: 0.222, 0.258 / 0.230, 0.244,
/// 2.2e-3, 4e-17); 24^3 level 0.280 (global 0.279), E - E0 - W 8.8e-3,
/// momentum 9.6e-5. 8% fewer particle updates than the global run in 40%
/// more sub-steps: the case's default stays global.
#[test]
fn block_steps_drive_the_same_turbulence() {
    let out = sph_validation::scratch("turbulence-16-block");
    let mut scene = sph_validation::scene("turbulence", 16);
    scene.config.time_steps = sph_core::TimeSteps::Block;
    let mass = scene.particles.m.iter().sum::<f64>();
    let n = scene.particles.m.len() as u64;
    let s = sph_validation::run(scene, Stop::Time(6.0 * T), &out);
    assert!(
        s.particle_updates < s.steps * n,
        "every sub-step updated every particle"
    );
    driven_checks(&out, mass, 3e-4, "16^3 block");
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

/// Columns `names` of every row of `conserved.csv` in `dir`.
fn conserved_columns<const K: usize>(dir: &Path, names: [&str; K]) -> Vec<[f64; K]> {
    let text = std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let cols = names.map(|n| header.iter().position(|h| *h == n).expect(n));
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            cols.map(|c| v[c])
        })
        .collect()
}

/// The work the driving's own field does on gas that does not answer it:
/// each particle, held at its initial position, takes the velocity
/// `u_i(t) = int_0^t a_s(x_i, t') dt'` (less the mass-weighted mean, as
/// the stage removes it), and the work is `1/2 sum m |u_i|^2`. The field
/// is `field`, a second [`Stirring`] of the run's, driven through the run's own
/// steps (`t`, `dt` of `conserved.csv`: the stage advances its OU phases by
/// the previous step, by `dt0` at the first), so it takes the very same
/// random path. Returns `W_free` at the start of each row's step.
fn free_particle_work(
    mut field: Stirring,
    p: &sph_core::Particles,
    dt0: f64,
    steps: &[[f64; 2]],
) -> Vec<f64> {
    let n = p.m.len();
    let mass: f64 = p.m.iter().sum();
    let mut u = vec![[0.0f64; 3]; n];
    let mut a = vec![[0.0f64; 3]; n];
    let mut work = Vec::with_capacity(steps.len());
    let mut dt_prev = dt0;
    for &[_, dt] in steps {
        work.push(
            0.5 * (0..n)
                .map(|i| p.m[i] * u[i].iter().map(|c| c * c).sum::<f64>())
                .sum::<f64>(),
        );
        field.advance(dt_prev);
        for (i, ai) in a.iter_mut().enumerate() {
            *ai = field.accelerate_one([p.x[i], p.y[i], p.z[i]]);
        }
        let mean = [0, 1, 2].map(|c| (0..n).map(|i| p.m[i] * a[i][c]).sum::<f64>() / mass);
        for (ui, ai) in u.iter_mut().zip(&a) {
            for c in 0..3 {
                ui[c] += (ai[c] - mean[c]) * dt;
            }
        }
        dt_prev = dt;
    }
    work
}

/// The injected work against the driving's analytic input. A purely
/// solenoidal driving (the case's, with `sol-weight=1`) of gas at rest
/// meets no pressure at linear order: until the flow has moved by a
/// fraction of the driving's wavelength, the gas takes the free-particle
/// work `1/2 sum m |int a_s dt|^2` of the field's own random path (OU
/// phases with correlation time T). The gap grows with the distance `d`
/// the gas has moved through the field, as `(k d)^2 / 2` for the dominant
/// `|k| L / 2 pi = 2`: `d ~ v t / 2` gives ~0.2% at T/8 and ~3% at T/4,
/// the bounds (measured 0.4% and 1.4%; 5% at T/2, 11% at 3T/4). The same
/// gas against a driving whose phases stay at their first values misses
/// both bounds (measured 2.4% at T/8, 5.3% at T/4); undriven gas does no
/// work at all.
#[test]
fn injected_work_follows_the_drivings_input() {
    let stir = StirParams {
        sol_weight: 1.0,
        ..StirParams::default()
    };
    let overrides = SchemeOverrides {
        stirring: Some(Some(stir)),
        ..Default::default()
    };
    let scene = sph_validation::scene_with("turbulence", 16, &overrides);
    let field = Stirring::new(stir, &scene.bbox).expect("the case's driving");
    let (initial, dt0) = (scene.particles.clone(), scene.dt0);
    let out = sph_validation::scratch("turbulence-16-input");
    sph_validation::run(scene, Stop::Time(0.3 * T), &out);
    let rows = conserved_columns(&out, ["t", "dt", "W_ext"]);
    let steps: Vec<[f64; 2]> = rows.iter().map(|r| [r[0], r[1]]).collect();
    let free = free_particle_work(field, &initial, dt0, &steps);
    for (frac, bound) in [(0.125, 0.01), (0.25, 0.03)] {
        let k = rows
            .iter()
            .position(|r| r[0] >= frac * T)
            .expect("the run reached the time");
        let (t, w, w_free) = (rows[k][0], rows[k][2] - rows[0][2], free[k]);
        let gap = w / w_free - 1.0;
        println!("t = {t:.4} ({frac} T): W {w:.4e}, free-particle {w_free:.4e}, gap {gap:+.2e}");
        assert!(
            gap.abs() < bound,
            "W {w:e} against the free-particle work {w_free:e} at t = {t}: {gap:+e}"
        );
    }
}
