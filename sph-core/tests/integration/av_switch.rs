//! Tests of the artificial-viscosity switches: exact IAD divergence of
//! linear flows, the grad(div v) shock indicator, the growth and the
//! exponential decay of alpha, its bounds, and momentum conservation with
//! per-particle alpha.

use crate::common::{self, kernel, Rng, Setup};

use proptest::prelude::*;
use sph_core::av_switch::{
    iad_and_velocity_divergence, shock_indicator, update_alpha, velocity_divergence,
    AvSwitchParams, FlowState,
};
use sph_core::density::{density, Positions};
use sph_core::iad::iad;
use sph_core::momentum::{
    momentum_energy, momentum_energy_switched, Gradients, HydroState, PairFactors, Rates,
};
use sph_core::{Eos, Particles};
use sph_tree::{Boundary, BoundingBox};

/// [`common::periodic_lattice`] with u = 1, density, IAD and the EOS
/// computed.
fn lattice(n: usize, jitter: f64, ng: f64, seed: u64) -> Setup {
    let mut s = common::periodic_lattice(n, jitter, ng, seed);
    s.p.u.fill(1.0);
    refresh(&mut s);
    s
}

/// Neighbour lists for the current h, density, IAD and the EOS.
fn refresh(s: &mut Setup) {
    common::symmetric_lists(&s.p, &s.bbox, &s.keys, &mut s.list);
    let p = &mut s.p;
    let pos = Positions {
        x: &p.x,
        y: &p.y,
        z: &p.z,
        h: &p.h,
        m: &p.m,
    };
    density(&kernel(), &s.bbox, pos, &s.list, &mut p.rho, &mut p.omega);
    iad(&kernel(), &s.bbox, pos, &p.rho, &s.list, &mut p.iad).unwrap();
    Eos::IdealGas { gamma: 5.0 / 3.0 }.apply(&p.rho, &p.u, None, &mut p.p, &mut p.c);
}

fn flow(p: &Particles) -> FlowState<'_> {
    FlowState {
        pos: Positions {
            x: &p.x,
            y: &p.y,
            z: &p.z,
            h: &p.h,
            m: &p.m,
        },
        vx: &p.vx,
        vy: &p.vy,
        vz: &p.vz,
        rho: &p.rho,
        c: &p.c,
        iad: std::array::from_fn(|k| p.iad[k].as_slice()),
    }
}

fn divergence(s: &Setup, gradients: Gradients) -> (Vec<f64>, Vec<f64>) {
    let (div_v, curl_v, _) = gradient(s, gradients);
    (div_v, curl_v)
}

/// Divergence, curl and the six symmetric-gradient fields.
fn gradient(s: &Setup, gradients: Gradients) -> (Vec<f64>, Vec<f64>, [Vec<f64>; 6]) {
    let n = s.p.len();
    let (mut div_v, mut curl_v) = (vec![0.0; n], vec![0.0; n]);
    let mut sym: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
    velocity_divergence(
        &kernel(),
        &s.bbox,
        flow(&s.p),
        gradients,
        &s.list,
        &mut div_v,
        &mut curl_v,
        &mut sym,
    );
    (div_v, curl_v, sym)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, failure_persistence: None, ..ProptestConfig::default() })]

    /// The fused IAD + velocity-gradient pass gives the matrices, the
    /// divergence and the curl of the two separate passes bit for bit.
    #[test]
    fn fused_iad_divergence_equals_separate_passes(seed in 0u64..1000, jitter in 0.0f64..0.8) {
        let mut s = lattice(7, jitter, 60.0, seed);
        let mut rng = Rng(seed ^ 0xABCD);
        for i in 0..s.p.len() {
            s.p.vx[i] = rng.uniform() - 0.5;
            s.p.vy[i] = rng.uniform() - 0.5;
            s.p.vz[i] = rng.uniform() - 0.5;
        }
        let (div_v, curl_v, sym) = gradient(&s, Gradients::Iad);
        let n = s.p.len();
        let mut c: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        let (mut div_f, mut curl_f) = (vec![0.0; n], vec![0.0; n]);
        let mut sym_f: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        let p = &s.p;
        let mut plain = flow(p);
        plain.iad = [&[]; 6];
        iad_and_velocity_divergence(
            &kernel(), &s.bbox, plain, [&p.m, &p.rho], &s.list, &mut c, &mut div_f, &mut curl_f,
            &mut sym_f,
        )
        .unwrap();
        for k in 0..6 {
            prop_assert!(sym_f[k].iter().zip(&sym[k]).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
        // The trace of the symmetric gradient is the divergence.
        for i in 0..n {
            let tr = sym[0][i] + sym[3][i] + sym[5][i];
            prop_assert!((tr - div_v[i]).abs() <= 1e-12 * (1.0 + div_v[i].abs()));
        }
        for k in 0..6 {
            prop_assert!(c[k].iter().zip(&p.iad[k]).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
        prop_assert!(div_f.iter().zip(&div_v).all(|(a, b)| a.to_bits() == b.to_bits()));
        prop_assert!(curl_f.iter().zip(&curl_v).all(|(a, b)| a.to_bits() == b.to_bits()));
        prop_assert!(div_v.iter().any(|&d| d != 0.0));
    }
}

fn indicator(s: &Setup, gradients: Gradients, div_v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = s.p.len();
    let (mut alpha_loc, mut v_sig) = (vec![0.0; n], vec![0.0; n]);
    shock_indicator(
        &kernel(),
        &s.bbox,
        flow(&s.p),
        gradients,
        div_v,
        &AvSwitchParams::default(),
        &s.list,
        &mut alpha_loc,
        &mut v_sig,
    );
    (alpha_loc, v_sig)
}

/// `steps` updates of alpha with time step `dt` (velocities fixed).
fn evolve_alpha(s: &Setup, params: &AvSwitchParams, alpha: &mut [f64], dt: f64, steps: usize) {
    let (div_v, _) = divergence(s, Gradients::Iad);
    for _ in 0..steps {
        update_alpha(
            &kernel(),
            &s.bbox,
            flow(&s.p),
            Gradients::Iad,
            &div_v,
            params,
            dt,
            &s.list,
            alpha,
        );
    }
}

/// A 12^3 lattice in an open box (a linear velocity field `v = v0 + G x`
/// is not periodic) with `d_a v_b = G[a][b]`.
fn linear_setup(jitter: f64, seed: u64) -> (Setup, [[f64; 3]; 3]) {
    let mut s = lattice(12, jitter, 100.0, seed);
    // Open box: particles near the faces have one-sided neighbourhoods,
    // which IAD handles exactly too.
    s.bbox = BoundingBox::cube(-0.6, 0.6, Boundary::Open).unwrap();
    s.keys = common::sort_along_curve(&mut s.p, &s.bbox);
    refresh(&mut s);
    // d_a v_b = g[a][b]
    let g = [[0.7, -1.3, 0.4], [2.1, -0.9, 0.25], [-0.6, 1.1, -1.7]];
    for i in 0..s.p.len() {
        let x = [s.p.x[i], s.p.y[i], s.p.z[i]];
        let v: [f64; 3] =
            std::array::from_fn(|b| 0.3 + g[0][b] * x[0] + g[1][b] * x[1] + g[2][b] * x[2]);
        (s.p.vx[i], s.p.vy[i], s.p.vz[i]) = (v[0], v[1], v[2]);
    }
    (s, g)
}

#[test]
fn iad_divergence_and_curl_of_linear_field_are_exact() {
    for jitter in [0.0, 0.6] {
        let (s, g) = linear_setup(jitter, 11);
        let div = g[0][0] + g[1][1] + g[2][2];
        let curl = [g[1][2] - g[2][1], g[2][0] - g[0][2], g[0][1] - g[1][0]];
        let curl = (curl[0] * curl[0] + curl[1] * curl[1] + curl[2] * curl[2]).sqrt();
        let (div_v, curl_v) = divergence(&s, Gradients::Iad);
        let mut worst: f64 = 0.0;
        for i in 0..s.p.len() {
            worst = worst
                .max((div_v[i] - div).abs())
                .max((curl_v[i] - curl).abs());
        }
        assert!(worst < 1e-10, "jitter {jitter}: max error {worst:e}");
        // Plain kernel gradients are only approximate (boundary particles
        // miss half their neighbours).
        let (div_k, _) = divergence(&s, Gradients::Kernel);
        let err = (0..s.p.len())
            .map(|i| (div_k[i] - div).abs())
            .fold(0.0, f64::max);
        assert!(err > 1e-3, "kernel divergence error only {err:e}");
    }
}

#[test]
fn indicator_vanishes_for_linear_field() {
    let (mut s, _) = linear_setup(0.6, 12);
    // Make the flow compressive everywhere (div v = -2.4 < 0).
    for i in 0..s.p.len() {
        s.p.vx[i] -= s.p.x[i];
    }
    let (div_v, _) = divergence(&s, Gradients::Iad);
    assert!(div_v.iter().all(|&d| d < 0.0));
    let (alpha_loc, _) = indicator(&s, Gradients::Iad, &div_v);
    let worst = alpha_loc.iter().cloned().fold(0.0, f64::max);
    assert!(worst < 1e-10, "alpha_loc up to {worst:e} in a linear flow");
}

/// A cold gas converging on the plane x = 0 with v_x = -V tanh(x / L).
fn converging(n: usize, jitter: f64, width: f64) -> Setup {
    let mut s = lattice(n, jitter, 100.0, 5);
    for i in 0..s.p.len() {
        s.p.vx[i] = -(s.p.x[i] / width).tanh();
        s.p.u[i] = 1e-6;
    }
    refresh(&mut s);
    s
}

#[test]
fn indicator_is_positive_in_converging_nonlinear_flow() {
    let s = converging(16, 0.3, 0.1);
    for gradients in [Gradients::Iad, Gradients::Kernel] {
        let (div_v, _) = divergence(&s, gradients);
        let (alpha_loc, _) = indicator(&s, gradients, &div_v);
        let mut compressive = 0;
        for i in 0..s.p.len() {
            let a = alpha_loc[i];
            assert!((0.0..=1.0).contains(&a), "alpha_loc = {a}");
            if div_v[i] < 0.0 {
                compressive += 1;
                assert!(a > 0.0, "particle at x = {}: alpha_loc = 0", s.p.x[i]);
            } else {
                assert_eq!(a, 0.0);
            }
        }
        assert!(compressive > s.p.len() / 4);
    }
}

#[test]
fn alpha_rises_in_compression_and_decays_where_expanding() {
    let s = converging(16, 0.3, 0.1);
    let params = AvSwitchParams::default();
    let mut alpha = vec![params.alpha_min; s.p.len()];
    evolve_alpha(&s, &params, &mut alpha, 1e-3, 1);
    // The steepening flanks of the compression switch to nearly alpha_max.
    let (div_v, _) = divergence(&s, Gradients::Iad);
    let max = alpha.iter().cloned().fold(0.0, f64::max);
    assert!(max > 0.9 * params.alpha_max, "max alpha {max}");
    let near = (0..s.p.len())
        .filter(|&i| div_v[i] < 0.0 && alpha[i] > 0.5)
        .count();
    assert!(near > 100, "only {near} particles above 0.5");
    // Where the flow expands (around x = +-0.5) alpha stays at alpha_min.
    for i in 0..s.p.len() {
        if div_v[i] > 0.0 {
            assert_eq!(alpha[i], params.alpha_min);
        }
    }
}

/// The weak-shock ceiling (`weak_alpha`) lifts alpha where a compression
/// is slow against the sound speed and leaves it where the gas is cold.
/// The same converging flow, hot (c = 10.5: pair Mach numbers about 0.2)
/// and cold (c = 1e-3: above 20 where anything approaches, so within 1%
/// of the strong ceiling), one update from alpha_min, with the ceiling
/// 0.5 at strong shocks and 2 at weak ones.
#[test]
fn weak_shock_ceiling_lifts_alpha_only_in_slow_compression() {
    let strong = AvSwitchParams {
        alpha_max: 0.5,
        ..AvSwitchParams::default()
    };
    let weak = AvSwitchParams {
        weak_alpha: Some(2.0),
        ..strong
    };
    let max_alpha = |s: &Setup, params: &AvSwitchParams| {
        let mut alpha = vec![params.alpha_min; s.p.len()];
        evolve_alpha(s, params, &mut alpha, 1e-3, 1);
        alpha
    };
    let cold = converging(16, 0.3, 0.1);
    let mut hot = converging(16, 0.3, 0.1);
    hot.p.u.iter_mut().for_each(|u| *u = 100.0);
    refresh(&mut hot);

    let (a, b) = (max_alpha(&cold, &strong), max_alpha(&cold, &weak));
    for i in 0..a.len() {
        assert!(
            b[i] <= a[i] * 1.01 + 1e-12,
            "cold particle {i}: {} against {}",
            b[i],
            a[i]
        );
    }
    let top = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    assert!(
        top(&a) > 0.4,
        "the cold compression switches on: {}",
        top(&a)
    );

    let (a, b) = (max_alpha(&hot, &strong), max_alpha(&hot, &weak));
    assert!(
        top(&a) <= 0.5 && top(&a) > 0.1,
        "hot, strong ceiling: {}",
        top(&a)
    );
    assert!(
        top(&b) > 2.5 * top(&a),
        "hot: {} against {}",
        top(&b),
        top(&a)
    );
    assert!(top(&b) <= 2.0);
}

#[test]
fn alpha_decays_exponentially_in_uniform_flow() {
    let mut s = lattice(12, 0.6, 100.0, 21);
    let mut rng = Rng(4);
    for i in 0..s.p.len() {
        (s.p.vx[i], s.p.vy[i], s.p.vz[i]) = (0.3, -0.2, 0.1);
        s.p.u[i] = 1.0 + rng.uniform();
    }
    refresh(&mut s);
    let params = AvSwitchParams::default();
    let (div_v, _) = divergence(&s, Gradients::Iad);
    assert!(div_v.iter().all(|&d| d == 0.0));
    let (alpha_loc, v_sig) = indicator(&s, Gradients::Iad, &div_v);
    assert!(alpha_loc.iter().all(|&a| a == 0.0));
    // No approaching pairs: v_sig = c_i + max_j c_j.
    for i in 0..s.p.len() {
        let cmax = s
            .list
            .neighbors(i)
            .filter(|&j| j != i)
            .map(|j| s.p.c[j])
            .fold(0.0, f64::max);
        assert_eq!(v_sig[i], s.p.c[i] + cmax);
    }
    let mut alpha: Vec<f64> = (0..s.p.len()).map(|_| 0.2 + 0.8 * rng.uniform()).collect();
    let start = alpha.clone();
    let (dt, steps) = (1e-2, 10);
    evolve_alpha(&s, &params, &mut alpha, dt, steps);
    let mut worst: f64 = 0.0;
    let mut decayed = 0.0;
    for i in 0..s.p.len() {
        let tau = s.p.h[i] / (params.decay * v_sig[i]);
        let expected =
            params.alpha_min + (start[i] - params.alpha_min) * (-(steps as f64) * dt / tau).exp();
        worst = worst.max((alpha[i] - expected).abs() / (expected - params.alpha_min));
        decayed += (start[i] - alpha[i]) / (start[i] - params.alpha_min);
    }
    assert!(worst < 1e-12, "relative deviation {worst:e}");
    // The decay is substantial over these steps (not a trivial pass).
    let mean = decayed / s.p.len() as f64;
    assert!(mean > 0.2 && mean < 0.9, "mean decayed fraction {mean}");
    // Long after, alpha sits at alpha_min.
    evolve_alpha(&s, &params, &mut alpha, 1e3, 1);
    assert!(alpha.iter().all(|&a| a == params.alpha_min));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    /// Whatever the flow, the starting alpha or the time step, alpha stays
    /// in [alpha_min, alpha_max] and is finite.
    #[test]
    fn alpha_stays_in_bounds(
        seed in any::<u64>(),
        dt in prop_oneof![Just(0.0), 1e-6..1e-2f64, 1e-2..1e3f64],
        iad_grad in any::<bool>(),
        amp in 0.01..10.0f64,
    ) {
        let mut s = lattice(8, 0.8, 50.0, seed);
        let mut rng = Rng(seed ^ 0x5eed);
        for i in 0..s.p.len() {
            s.p.vx[i] = amp * (rng.uniform() - 0.5);
            s.p.vy[i] = amp * (rng.uniform() - 0.5);
            s.p.vz[i] = amp * (rng.uniform() - 0.5);
            s.p.u[i] = 0.01 + rng.uniform();
        }
        refresh(&mut s);
        let params = AvSwitchParams {
            alpha_min: 0.01 + 0.2 * rng.uniform(),
            alpha_max: 0.5 + rng.uniform(),
            ..Default::default()
        };
        let gradients = if iad_grad { Gradients::Iad } else { Gradients::Kernel };
        let (div_v, _) = divergence(&s, gradients);
        // Starting values inside and outside the bounds.
        let mut alpha: Vec<f64> = (0..s.p.len()).map(|_| 2.0 * rng.uniform() - 0.5).collect();
        for _ in 0..3 {
            update_alpha(&kernel(), &s.bbox, flow(&s.p), gradients, &div_v, &params, dt, &s.list, &mut alpha);
            for &a in &alpha {
                prop_assert!(a >= params.alpha_min && a <= params.alpha_max, "alpha = {}", a);
            }
        }
    }

    /// The weak-shock ceiling lies between `alpha_max` and `weak_alpha`,
    /// equals `weak_alpha` at rest and moves monotonically towards
    /// `alpha_max` as the pair Mach number grows.
    #[test]
    fn ceiling_is_between_its_ends_and_monotone(
        alpha_max in 0.0..3.0f64,
        weak in 0.0..3.0f64,
        m1 in 0.0..50.0f64,
        dm in 0.0..50.0f64,
    ) {
        let p = AvSwitchParams { alpha_max, weak_alpha: Some(weak), ..AvSwitchParams::default() };
        let (lo, hi) = (alpha_max.min(weak), alpha_max.max(weak));
        let (c1, c2) = (p.ceiling(m1), p.ceiling(m1 + dm));
        prop_assert!(c1 >= lo - 1e-12 && c1 <= hi + 1e-12, "{}", c1);
        prop_assert!((p.ceiling(0.0) - weak).abs() < 1e-12);
        // Farther from alpha_max at the lower Mach number.
        prop_assert!((c1 - alpha_max).abs() >= (c2 - alpha_max).abs() - 1e-12);
        prop_assert_eq!(AvSwitchParams { weak_alpha: None, ..p }.ceiling(m1), alpha_max);
    }

    /// The relaxation alone: bounded, monotone towards its target, and a
    /// jump exactly to alpha_loc when that is larger.
    #[test]
    fn advance_is_bounded_and_monotone(
        alpha in 0.05..1.0f64,
        alpha_loc in 0.0..1.0f64,
        tau in 1e-6..1e3f64,
        dt in 0.0..1e3f64,
    ) {
        let p = AvSwitchParams::default();
        let a = p.advance(alpha, alpha_loc, tau, dt);
        prop_assert!(a >= p.alpha_min && a <= p.alpha_max);
        if alpha_loc >= alpha {
            prop_assert_eq!(a, alpha_loc);
        } else {
            let target = alpha_loc.max(p.alpha_min);
            prop_assert!(a <= alpha && a >= target);
        }
    }

    /// Per-particle alpha keeps the pair forces antisymmetric: one force
    /// evaluation changes the total momentum by round-off only, and total
    /// energy is still conserved by the rates.
    #[test]
    fn switched_viscosity_conserves_momentum_and_energy(seed in any::<u64>(), iad_grad in any::<bool>()) {
        let mut s = lattice(10, 0.8, 60.0, seed);
        let mut rng = Rng(seed ^ 0xABCD);
        for i in 0..s.p.len() {
            common::random_flow(&mut s.p, i, || rng.uniform());
            s.p.h[i] *= 1.0 + 0.5 * (rng.uniform() - 0.5);
        }
        refresh(&mut s);
        let alpha: Vec<f64> = (0..s.p.len()).map(|_| 0.05 + 0.95 * rng.uniform()).collect();
        let gradients = if iad_grad { Gradients::Iad } else { Gradients::Kernel };
        forces(&mut s, gradients, Some(&alpha));
        let (momentum, energy) = common::conservation_errors(&s.p);
        prop_assert!(momentum < 1e-13, "momentum {momentum:e}");
        prop_assert!(energy < 1e-12, "energy rate {energy:e}");
    }
}

/// Forces with a constant alpha = 1 (`None`) or per-particle alpha.
fn forces(s: &mut Setup, gradients: Gradients, alpha: Option<&[f64]>) {
    let p = &mut s.p;
    let state = HydroState {
        pos: Positions {
            x: &p.x,
            y: &p.y,
            z: &p.z,
            h: &p.h,
            m: &p.m,
        },
        vx: &p.vx,
        vy: &p.vy,
        vz: &p.vz,
        rho: &p.rho,
        p: &p.p,
        c: &p.c,
        omega: &p.omega,
        iad: std::array::from_fn(|k| p.iad[k].as_slice()),
    };
    let rates = Rates {
        ax: &mut p.ax,
        ay: &mut p.ay,
        az: &mut p.az,
        du: &mut p.du,
        criteria: None,
        impulse: None,
    };
    let mut factors = PairFactors::default();
    factors.fill(&state);
    let k = kernel();
    match alpha {
        None => momentum_energy(&k, &s.bbox, state, &factors, gradients, 0.7, &s.list, rates),
        Some(a) => {
            momentum_energy_switched(&k, &s.bbox, state, &factors, gradients, a, &s.list, rates)
        }
    };
}

#[test]
fn equal_switches_reproduce_constant_alpha_bit_for_bit() {
    let mut s = lattice(10, 0.8, 60.0, 99);
    let mut rng = Rng(17);
    for i in 0..s.p.len() {
        s.p.vx[i] = rng.uniform() - 0.5;
        s.p.vy[i] = rng.uniform() - 0.5;
        s.p.vz[i] = rng.uniform() - 0.5;
    }
    refresh(&mut s);
    for gradients in [Gradients::Iad, Gradients::Kernel] {
        forces(&mut s, gradients, None);
        let constant = (
            s.p.ax.clone(),
            s.p.ay.clone(),
            s.p.az.clone(),
            s.p.du.clone(),
        );
        let alpha = vec![0.7; s.p.len()];
        forces(&mut s, gradients, Some(&alpha));
        assert_eq!(constant.0, s.p.ax);
        assert_eq!(constant.1, s.p.ay);
        assert_eq!(constant.2, s.p.az);
        assert_eq!(constant.3, s.p.du);
        // And a different alpha changes the viscous terms.
        let alpha = vec![0.2; s.p.len()];
        forces(&mut s, gradients, Some(&alpha));
        assert_ne!(constant.3, s.p.du);
    }
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let s = converging(10, 0.5, 0.1);
    let params = AvSwitchParams::default();
    let run = || {
        let (div_v, curl_v) = divergence(&s, Gradients::Iad);
        let mut alpha = vec![params.alpha_min; s.p.len()];
        evolve_alpha(&s, &params, &mut alpha, 1e-3, 2);
        (div_v, curl_v, alpha)
    };
    let many = run();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(run);
    assert_eq!(many, one);
}

/// The lattice of [`linear_setup`] with the velocity field `v = G x`,
/// `d_a v_b = g[a][b]`, and the Balsara factors of its particles at least
/// two smoothing lengths inside the box.
fn balsara_of(g: [[f64; 3]; 3]) -> Vec<f64> {
    let (mut s, _) = linear_setup(0.0, 5);
    for i in 0..s.p.len() {
        let x = [s.p.x[i], s.p.y[i], s.p.z[i]];
        let v: [f64; 3] = std::array::from_fn(|b| g[0][b] * x[0] + g[1][b] * x[1] + g[2][b] * x[2]);
        (s.p.vx[i], s.p.vy[i], s.p.vz[i]) = (v[0], v[1], v[2]);
        s.p.u[i] = 1.0;
    }
    refresh(&mut s);
    let (div_v, curl_v) = divergence(&s, Gradients::Iad);
    let p = &s.p;
    (0..p.len())
        .filter(|&i| {
            [p.x[i], p.y[i], p.z[i]]
                .iter()
                .all(|c| c.abs() < 0.5 - 2.0 * p.h[i])
        })
        .map(|i| sph_core::av_switch::balsara(div_v[i], curl_v[i], p.c[i], p.h[i]))
        .collect()
}

#[test]
fn balsara_factor_is_zero_in_shear_and_one_in_compression() {
    // Pure shear v_x = y: div v = 0, |curl v| = 1.
    let shear = balsara_of([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]);
    assert!(!shear.is_empty());
    let worst = shear.iter().cloned().fold(0.0, f64::max);
    assert!(worst < 1e-9, "shear: Balsara factor up to {worst:e}");
    // Pure compression v = -x: curl v = 0, div v = -3 (c ~ 0.8, h ~ 0.24).
    let squeeze = balsara_of([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
    let least = squeeze.iter().cloned().fold(1.0, f64::min);
    assert!(least > 0.999, "compression: Balsara factor down to {least}");
}
