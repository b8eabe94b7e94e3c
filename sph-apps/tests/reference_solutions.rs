//! The analytic references (`sph_apps::reference`) against independent oracles: the Sedov
//! profiles in `tests/data/*.csv`, the numbers of `docs/cases.md`, conservation integrals
//! and the Rankine-Hugoniot jump conditions.

use std::f64::consts::PI;
use std::sync::OnceLock;
use std::time::Instant;

use proptest::prelude::*;
use sph_apps::reference::{FlowState, Noh, ReferenceError, Sedov};

const GAMMA: f64 = 5.0 / 3.0;
const SEDOV_T005: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/sedov_t0.05.csv");
const SEDOV_T009: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/sedov_t0.09.csv");

/// The Sedov case of `docs/cases.md`: gamma 5/3, E = 1, rho0 = 1, 3-D, ambient labelled as the CSV.
fn sedov() -> &'static Sedov {
    static SEDOV: OnceLock<Sedov> = OnceLock::new();
    SEDOV.get_or_init(|| {
        Sedov::spherical(GAMMA, 1.0, 1.0)
            .expect("valid parameters")
            .with_ambient(0.0, 1e-8)
    })
}

fn rel(got: f64, want: f64) -> f64 {
    (got / want - 1.0).abs()
}

/// Composite Simpson with `n` (even) intervals; deliberately not the crate's quadrature.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let inner: f64 = (1..n)
        .map(|i| f(a + h * i as f64) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    h / 3.0 * (f(a) + inner + f(b))
}

// ---------------------------------------------------------------------------------------------
// Sedov against the independent CSV profiles.
// ---------------------------------------------------------------------------------------------

/// One CSV row: r, rho, u, p, v.
struct Row([f64; 5]);

fn read_oracle(path: &str) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| {
        panic!(
            "cannot read the Sedov oracle {path}: {e}. It ships with the crate in \
             sph-apps/tests/data/ (see its README.md); this comparison must not be skipped"
        )
    });
    let rows: Vec<Row> = text
        .lines()
        .filter(|line| !line.starts_with('#') && !line.trim().is_empty())
        .map(|line| {
            let cols: Vec<f64> = line
                .split(',')
                .map(|x| x.trim().parse().expect("numeric CSV field"))
                .collect();
            Row(cols.try_into().expect("5 columns: r,rho,u,p,v"))
        })
        .collect();
    assert_eq!(
        rows.len(),
        445,
        "{path}: expected 445 rows (tests/data/README.md)"
    );
    rows
}

/// Compares every row of one oracle file; returns the worst relative error of rho, p, v, u
/// over the region checked at 1e-5.
///
/// Tolerances, from what limits the oracle (printed to 8 significant digits, so ~5e-8) and
/// this solution (interpolation ~1e-12):
/// - `lambda = r/R >= 0.03`: relative 1e-5 on rho, p, v, u (measured: < 4e-7).
/// - `lambda < 0.03` (core, rho < 2e-7 rho0): an implementation that solves for `V` in double
///   precision, as the oracle does, cannot resolve `V - V0 ~ lambda^6.5` there, and its
///   density drifts (8% at lambda = 0.006). So: rho absolute 1e-6, v absolute 1e-4 v_s, p
///   relative 1e-5 -- except the first row (lambda = 1e-5), where `V - V0 ~ 1e-32` and the
///   oracle's pressure is 4.6% below its own plateau; there p within 5%. The core itself is
///   checked against the exact central asymptotics in `sedov_centre_asymptotics`.
/// - the one row sampled at the shock radius printed to 8 digits (`|lambda - 1| < 1e-7`)
///   straddles the discontinuity and is skipped; every other row beyond is the exact ambient.
fn compare_with_oracle(path: &str, t: f64) -> [f64; 4] {
    let sedov = sedov();
    let radius = sedov.shock_radius(t);
    let post = sedov.post_shock(t);
    let mut worst = [0.0_f64; 4];
    let mut straddling = 0;
    for Row([r, rho, u, p, v]) in read_oracle(path) {
        let got = sedov.state(r, t);
        let lambda = r / radius;
        let at = format!("t = {t}, r = {r} (lambda = {lambda:.6}): got {got:?}");
        if (lambda - 1.0).abs() < 1e-7 {
            straddling += 1;
        } else if lambda > 1.0 {
            let want = FlowState { rho, p, v, u };
            assert_eq!(got, want, "{at}");
        } else if lambda >= 0.03 {
            let errors = [
                rel(got.rho, rho),
                rel(got.p, p),
                rel(got.v, v),
                rel(got.u, u),
            ];
            for (w, e) in worst.iter_mut().zip(errors) {
                *w = w.max(e);
            }
            assert!(
                errors.iter().all(|&e| e < 1e-5),
                "{at}; oracle rho {rho} p {p} v {v} u {u}"
            );
        } else {
            assert!((got.rho - rho).abs() < 1e-6, "{at}; oracle rho {rho}");
            assert!((got.v - v).abs() < 1e-4 * post.v, "{at}; oracle v {v}");
            let p_tol = if lambda >= 1e-3 { 1e-5 } else { 0.05 };
            assert!(rel(got.p, p) < p_tol, "{at}; oracle p {p}");
        }
    }
    assert!(
        straddling <= 1,
        "{path}: {straddling} rows within 1e-7 R of the shock"
    );
    let [e_rho, e_p, e_v, e_u] = worst;
    eprintln!(
        "{path}: worst relative error for lambda >= 0.03: \
         rho {e_rho:.1e}, p {e_p:.1e}, v {e_v:.1e}, u {e_u:.1e}"
    );
    worst
}

#[test]
fn sedov_matches_oracle_at_t005() {
    compare_with_oracle(SEDOV_T005, 0.05);
}

#[test]
fn sedov_matches_oracle_at_t009() {
    compare_with_oracle(SEDOV_T009, 0.09);
}

// ---------------------------------------------------------------------------------------------
// Sedov: headline numbers, energy, asymptotics, API behaviour.
// ---------------------------------------------------------------------------------------------

#[test]
fn sedov_validation_numbers() {
    let sedov = sedov();
    assert!(
        (sedov.xi0() - 1.15167).abs() < 1e-4,
        "xi0 = {}",
        sedov.xi0()
    );
    assert!((sedov.shock_radius(0.05) - 0.34747).abs() < 1e-4);
    assert!((sedov.shock_radius(0.09) - 0.43957).abs() < 1e-4);
    for (t, p_s, v_s) in [(0.05, 5.7952, 2.0848), (0.09, 2.8625, 1.4652)] {
        let post = sedov.post_shock(t);
        assert!((post.rho - 4.0).abs() < 1e-12, "{post:?}");
        assert!((post.p - p_s).abs() < 1e-4, "t = {t}: {post:?}");
        assert!((post.v - v_s).abs() < 1e-4, "t = {t}: {post:?}");
        // The jump conditions of a strong shock, from the shock speed alone.
        let speed = sedov.shock_speed(t);
        assert!(rel(post.v, 0.75 * speed) < 1e-12);
        assert!(rel(post.p, 0.75 * speed * speed) < 1e-12);
    }
}

#[test]
fn sedov_alpha_matches_kamm_timmes_tables() {
    // Kamm & Timmes (2007) quote alpha = 0.9840 (cylindrical) and 0.8510 (spherical) for
    // gamma = 1.4.
    for (j, alpha) in [(2, 0.9840), (3, 0.8510)] {
        let sedov = Sedov::new(1.4, 1.0, 1.0, j).unwrap();
        assert!(
            (sedov.alpha() - alpha).abs() < 1e-4,
            "j = {j}: {}",
            sedov.alpha()
        );
    }
}

/// `E = A_j ∫_0^R (rho v^2/2 + p/(gamma-1)) r^(j-1) dr` with the interpolated profile: checks
/// alpha, the profile and the jump scales together (alpha comes from a separate quadrature of
/// the closed forms).
fn energy_behind_shock(sedov: &Sedov, t: f64) -> f64 {
    let j = sedov.geometry();
    let area = match j {
        1 => 1.0,
        2 => 2.0 * PI,
        _ => 4.0 * PI,
    };
    let gm1 = sedov.gamma() - 1.0;
    let density = |r: f64| {
        let s = sedov.state(r, t);
        area * r.powi(j as i32 - 1) * (0.5 * s.rho * s.v * s.v + s.p / gm1)
    };
    simpson(density, 0.0, sedov.shock_radius(t), 20_000)
}

#[test]
fn sedov_energy_integral_equals_blast_energy() {
    for (gamma, j, energy, rho0, t) in [
        (GAMMA, 3, 1.0, 1.0, 0.05),
        (GAMMA, 3, 1.0, 1.0, 0.09),
        (1.4, 3, 2.5, 0.7, 0.3),
        (GAMMA, 2, 1.0, 1.0, 0.05),
        (1.4, 2, 3.0, 2.0, 1.0),
        (GAMMA, 1, 1.0, 1.0, 0.05),
        (1.4, 1, 0.5, 1.5, 2.0),
    ] {
        let sedov = Sedov::new(gamma, energy, rho0, j).unwrap();
        let e = energy_behind_shock(&sedov, t);
        assert!(
            rel(e, energy) < 1e-6,
            "gamma {gamma} j {j}: E = {e}, want {energy}"
        );
    }
}

#[test]
fn sedov_centre_asymptotics() {
    // Near the centre V -> V0 = 2/((j+2) gamma): v = 2 r/((j+2) gamma t), rho ~ r^(j/(gamma-1)),
    // p -> const; the corrections are O(lambda^6.5) for gamma = 5/3, j = 3.
    let sedov = sedov();
    let t = 0.05;
    let radius = sedov.shock_radius(t);
    for lambda in [1e-3, 1e-5, 1e-7, 1e-9] {
        let r = lambda * radius;
        let (s, half) = (sedov.state(r, t), sedov.state(0.5 * r, t));
        assert!(
            rel(s.v, 2.0 * r / (5.0 * GAMMA * t)) < 1e-9,
            "lambda {lambda}: {s:?}"
        );
        assert!(
            rel(s.rho / half.rho, 2f64.powf(4.5)) < 1e-9,
            "lambda {lambda}"
        );
        assert!(rel(s.p, half.p) < 1e-9, "lambda {lambda}");
    }
    let centre = sedov.state(0.0, t);
    assert_eq!((centre.rho, centre.v), (0.0, 0.0));
    assert!(centre.p.is_finite() && centre.p > 0.0 && centre.u == f64::INFINITY);
}

#[test]
fn sedov_outside_and_before_the_blast_is_ambient() {
    let sedov = Sedov::spherical(GAMMA, 1.0, 2.0)
        .unwrap()
        .with_ambient(1e-5, 3e-6);
    let ambient = FlowState {
        rho: 2.0,
        p: 1e-5,
        v: 0.0,
        u: 3e-6,
    };
    let radius = sedov.shock_radius(0.1);
    assert_eq!(sedov.state(radius * (1.0 + 1e-12), 0.1), ambient);
    assert_eq!(sedov.state(5.0, 0.1), ambient);
    assert_eq!(sedov.state(0.1, 0.0), ambient);
    assert_eq!(sedov.state(0.0, -1.0), ambient);
    assert_eq!(sedov.shock_radius(-1.0), 0.0);
    assert_eq!(sedov.state(-0.1, 0.1), sedov.state(0.1, 0.1));
    assert!(sedov.state(f64::NAN, 0.1).rho.is_nan());
}

#[test]
fn sedov_rejects_bad_parameters() {
    let cases: [(Result<Sedov, ReferenceError>, &str); 9] = [
        (Sedov::spherical(1.0, 1.0, 1.0), "gamma = 1"),
        (Sedov::spherical(f64::NAN, 1.0, 1.0), "gamma = NaN"),
        (Sedov::spherical(GAMMA, 0.0, 1.0), "E = 0"),
        (Sedov::spherical(GAMMA, f64::INFINITY, 1.0), "E = inf"),
        (Sedov::spherical(GAMMA, 1.0, -1.0), "rho0 = -1"),
        (Sedov::new(GAMMA, 1.0, 1.0, 0), "j = 0"),
        (Sedov::new(GAMMA, 1.0, 1.0, 4), "j = 4"),
        (Sedov::spherical(2.0, 1.0, 1.0), "gamma = 2"),
        (Sedov::spherical(7.0, 1.0, 1.0), "gamma = 7"),
    ];
    for (result, needle) in cases {
        let message = result.expect_err(needle).to_string();
        assert!(
            message.contains(needle),
            "{message:?} should name {needle:?}"
        );
    }
    assert!(matches!(
        Sedov::new(2.0, 1.0, 1.0, 1),
        Err(ReferenceError::UnsupportedGamma { geometry: 1, .. })
    ));
    // gamma >= 7 is singular only in spherical geometry.
    assert!(Sedov::new(8.0, 1.0, 1.0, 2).is_ok());
}

#[test]
fn sedov_state_is_fast() {
    // The L1 drivers evaluate the reference at every particle radius.
    let sedov = sedov();
    let n = 1_000_000;
    let radius = sedov.shock_radius(0.09);
    let start = Instant::now();
    let total: f64 = (0..n)
        .map(|i| sedov.state(1.2 * radius * i as f64 / n as f64, 0.09).rho)
        .sum();
    let elapsed = start.elapsed();
    eprintln!("Sedov::state: {n} evaluations in {elapsed:?}");
    assert!(total.is_finite());
    assert!(elapsed.as_secs_f64() < 10.0, "{elapsed:?}");
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: None,
        ..ProptestConfig::with_cases(256)
    })]

    /// Density rises monotonically from the centre to the shock and reaches the jump value.
    #[test]
    fn sedov_density_monotone_and_continuous_at_shock(
        t in 1e-3_f64..1.0,
        a in 1e-6_f64..1.0,
        b in 1e-6_f64..1.0,
    ) {
        let sedov = sedov();
        let radius = sedov.shock_radius(t);
        let (lo, hi) = (a.min(b), a.max(b));
        prop_assert!(sedov.state(lo * radius, t).rho <= sedov.state(hi * radius, t).rho);
        let jump = sedov.post_shock(t).rho;
        let inside = sedov.state(radius * (1.0 - 1e-9), t).rho;
        prop_assert!((inside - jump).abs() < 1e-6, "{inside} vs {jump}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: None,
        ..ProptestConfig::with_cases(24)
    })]

    /// Across gamma and geometry: the profile carries exactly the blast energy, the density is
    /// monotone and meets the jump `(gamma+1)/(gamma-1) rho0`.
    #[test]
    fn sedov_energy_and_shape_for_any_gamma(
        gamma in prop_oneof![1.1_f64..1.99, 2.01_f64..6.9],
        j in 1_u32..=3,
        t in 0.01_f64..1.0,
    ) {
        let sedov = Sedov::new(gamma, 1.0, 1.0, j).unwrap();
        let e = energy_behind_shock(&sedov, t);
        prop_assert!(rel(e, 1.0) < 1e-6, "E = {e}");
        let radius = sedov.shock_radius(t);
        let mut previous = 0.0;
        for k in 1..=200 {
            // radius * 1.0 is the shock itself (radius * 200 / 200 may round past it).
            let rho = sedov.state(radius * (k as f64 / 200.0), t).rho;
            prop_assert!(rho >= previous, "not monotone at {k}/200");
            previous = rho;
        }
        prop_assert!(rel(previous, (gamma + 1.0) / (gamma - 1.0)) < 1e-12);
    }
}

// ---------------------------------------------------------------------------------------------
// Noh.
// ---------------------------------------------------------------------------------------------

#[test]
fn noh_validation_numbers() {
    // VALIDATION.md: use the particle set's own rho0, not 1.
    let rho0 = 0.8;
    let noh = Noh::new(GAMMA, rho0, 1.0).unwrap();
    let t = 0.6;
    assert!((noh.shock_radius(t) - t / 3.0).abs() < 1e-15);
    let inside = noh.state(0.1, t);
    assert!(rel(inside.rho, 64.0 * rho0) < 1e-14);
    assert!(rel(inside.u, 0.5) < 1e-14);
    assert!(rel(inside.p, 64.0 / 3.0 * rho0) < 1e-14);
    assert_eq!(inside.v, 0.0);
    for r in [0.21, 0.3, 0.5, 2.0] {
        let outside = noh.state(r, t);
        assert!(rel(outside.rho, rho0 * (1.0 + t / r).powi(2)) < 1e-14);
        // Signed radial velocity: the gas falls inwards.
        assert_eq!((outside.v, outside.p, outside.u), (-1.0, 0.0, 0.0));
    }
    assert_eq!(Noh::default(), Noh::new(GAMMA, 1.0, 1.0).unwrap());
}

#[test]
fn noh_initial_state_and_ambient_energy() {
    let noh = Noh::new(1.4, 2.0, 3.0).unwrap().with_ambient_u(1e-6);
    let initial = noh.state(0.3, 0.0);
    assert_eq!((initial.rho, initial.v, initial.u), (2.0, -3.0, 1e-6));
    let outside = noh.state(1.0, 0.1);
    assert!(rel(outside.p, 0.4 * outside.rho * 1e-6) < 1e-14);
    // The shocked state ignores the label.
    assert!(rel(noh.state(0.0, 0.1).u, 4.5) < 1e-14);
    assert!(noh.state(f64::NAN, 0.1).rho.is_nan());
}

#[test]
fn noh_conserves_mass() {
    // All the mass initially inside R_out + v0 t is inside R_out at t.
    for (gamma, rho0, v0, t, r_out) in [
        (GAMMA, 1.0, 1.0, 0.6, 0.5),
        (1.4, 0.3, 2.0, 0.25, 1.0),
        (3.0, 5.0, 0.5, 1.0, 0.8),
    ] {
        let noh = Noh::new(gamma, rho0, v0).unwrap();
        let shell = |r: f64| 4.0 * PI * r * r * noh.state(r, t).rho;
        let r_s = noh.shock_radius(t);
        assert!(r_s < r_out);
        // The shock itself reports the shocked state: start the outer part just beyond it.
        let outer = simpson(shell, r_s * (1.0 + 1e-15), r_out, 20_000);
        let mass = simpson(shell, 0.0, r_s, 2_000) + outer;
        let want = 4.0 / 3.0 * PI * rho0 * (r_out + v0 * t).powi(3);
        assert!(rel(mass, want) < 1e-6, "gamma {gamma}: {mass} vs {want}");
    }
}

#[test]
fn noh_rejects_bad_parameters() {
    for (result, needle) in [
        (Noh::new(0.5, 1.0, 1.0), "gamma = 0.5"),
        (Noh::new(GAMMA, 0.0, 1.0), "rho0 = 0"),
        (Noh::new(GAMMA, 1.0, -1.0), "v0 = -1"),
        (Noh::new(GAMMA, 1.0, f64::NAN), "v0 = NaN"),
    ] {
        let message = result.expect_err(needle).to_string();
        assert!(
            message.contains(needle),
            "{message:?} should name {needle:?}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Mass, momentum and energy fluxes through the shock, in its rest frame, agree on both
    /// sides.
    #[test]
    fn noh_rankine_hugoniot(
        gamma in 1.05_f64..5.0,
        rho0 in 0.1_f64..10.0,
        v0 in 0.1_f64..10.0,
        t in 0.01_f64..10.0,
    ) {
        let noh = Noh::new(gamma, rho0, v0).unwrap();
        let r_s = noh.shock_radius(t);
        let s = noh.shock_speed();
        let up = noh.state(r_s * (1.0 + 1e-14), t);
        let down = noh.state(r_s, t);
        let (w_up, w_down) = (up.v - s, down.v - s);
        let mass = (up.rho * w_up, down.rho * w_down);
        let momentum = (up.rho * w_up * w_up + up.p, down.rho * w_down * w_down + down.p);
        let enthalpy = (
            up.u + up.p / up.rho + 0.5 * w_up * w_up,
            down.u + down.p / down.rho + 0.5 * w_down * w_down,
        );
        for (a, b) in [mass, momentum, enthalpy] {
            prop_assert!(rel(a, b) < 1e-10, "{a} vs {b}");
        }
    }
}
