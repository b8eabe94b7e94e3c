//! Block time steps (`TimeSteps::Block`, issue 41): a uniform state keeps
//! one bin and then is the one-bin integrator (`TimeSteps::Kdk`) bit for
//! bit; the limiter keeps every active particle's bin within its factor of
//! its neighbours' (and without it a blast breaks that); results do not
//! depend on the thread count; a blast is advanced with a fraction of the
//! global run's particle updates and its energy kept.

use sph_core::timeline::{is_active, Bin};
use sph_core::timestep::FirstStep;
use sph_core::{Conserved, Hydro, HydroConfig, Particles, Scheme, StepReport, TimeSteps, PRESETS};
use sph_kernels::{Sinc, Tabulated};
use sph_tree::{Boundary, BoundingBox};

const SIDE: usize = 10;

/// A 10^3 lattice in a periodic unit box with internal energy `u(r)`.
fn lattice(config: &HydroConfig, u: impl Fn([f64; 3]) -> f64) -> Particles {
    let n = SIDE;
    let mut p = Particles::new(n * n * n, config.fields());
    for i in 0..p.len() {
        let c = [i % n, i / n % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64 - 0.5);
        (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
        p.m[i] = 1.0 / p.len() as f64;
        p.h[i] = 1.3 / n as f64;
        p.u[i] = u(c);
        p.id[i] = i as u64;
    }
    p
}

fn config(time_steps: TimeSteps, limiter: bool) -> HydroConfig {
    let mut config = HydroConfig::with_scheme(Scheme::PAPER);
    config.time_steps = time_steps;
    config.timestep.first_step = FirstStep::Criteria;
    config.timestep.limiter = limiter;
    config.neighbors.ng0 = 60;
    config.neighbors.ngmax = 90;
    config
}

fn blast(c: [f64; 3]) -> f64 {
    1e-4 + 100.0 * (-(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 0.01).exp()
}

/// What one sub-step saw: the bins before and after it, the tick it ran
/// at, the positions and smoothing lengths it ran with, ids in order.
struct Seen {
    before: Vec<f64>,
    after: Vec<f64>,
    ti: u64,
    x: [Vec<f64>; 3],
    h: Vec<f64>,
    report: StepReport,
}

/// Runs `steps` steps of `config` on the lattice with `u`, to the end
/// time `t_end`; returns the final particles and what each step saw.
fn run(
    config: HydroConfig,
    u: impl Fn([f64; 3]) -> f64,
    t_end: f64,
    steps: usize,
) -> (Particles, Vec<Seen>) {
    let mut p = lattice(&config, u);
    let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
    let mut hydro = Hydro::new(kernel, config, 0.0, 1e-4).unwrap();
    hydro.prepare(&mut p);
    hydro.set_time_line(t_end).unwrap();
    let mut seen = Vec::new();
    for _ in 0..steps {
        if hydro.time() >= t_end {
            break;
        }
        let ti = hydro.tick();
        let before = by_id(&p, &p.bin);
        let x = [by_id(&p, &p.x), by_id(&p, &p.y), by_id(&p, &p.z)];
        let h = by_id(&p, &p.h);
        let report = hydro.step(&mut p, &mut bbox).unwrap();
        seen.push(Seen {
            before,
            after: by_id(&p, &p.bin),
            ti,
            x,
            h,
            report,
        });
    }
    (p, seen)
}

/// Runs `config` on the lattice with `u` on a line to t = 1 whose
/// longest step is `dt_max`, up to its first synchronisation point (every
/// particle's step ends there); returns the final particles (their steps
/// closed: [`Hydro::evaluate_closed`]), the relative change of the total
/// energy, and the largest spread of bins any sub-step had.
fn run_to_sync(
    mut config: HydroConfig,
    u: impl Fn([f64; 3]) -> f64,
    dt_max: f64,
) -> (Particles, f64, f64) {
    config.timestep.dt_max = Some(dt_max);
    let mut p = lattice(&config, u);
    let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
    let e0: f64 = (0..p.len()).map(|i| p.m[i] * p.u[i]).sum();
    let mut hydro = Hydro::new(kernel, config, 0.0, 1e-4).unwrap();
    hydro.prepare(&mut p);
    hydro.set_time_line(1.0).unwrap();
    let mut spread: f64 = 0.0;
    while hydro.time() < dt_max {
        let report = hydro.step(&mut p, &mut bbox).unwrap();
        let (lo, hi) = p.bin.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &b| {
            (lo.min(b), hi.max(b))
        });
        spread = spread.max(hi - lo);
        if report.ends_synchronised {
            break;
        }
    }
    hydro.evaluate_closed(&mut p, &mut bbox).unwrap();
    let e = Conserved::compute(&p, hydro.owned(), [], hydro.domain().comm())
        .0
        .e_tot();
    (p, e / e0 - 1.0, spread)
}

/// `field` ordered by particle id.
fn by_id(p: &Particles, field: &[f64]) -> Vec<f64> {
    let mut v = vec![0.0; p.len()];
    for i in 0..p.len() {
        v[p.id[i] as usize] = field[i];
    }
    v
}

/// Pairs of neighbours (`r < 2 max(h_i, h_j)`, periodic unit box).
fn neighbour_pairs(s: &Seen) -> Vec<(usize, usize)> {
    let n = s.h.len();
    let mut pairs = Vec::new();
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let r2: f64 = (0..3)
                .map(|k| {
                    let d = s.x[k][i] - s.x[k][j];
                    let d = d - d.round();
                    d * d
                })
                .sum();
            let reach = 2.0 * s.h[i].max(s.h[j]);
            if r2 < reach * reach {
                pairs.push((i, j));
            }
        }
    }
    pairs
}

#[test]
fn a_uniform_state_keeps_one_bin_and_is_the_one_bin_run_bit_for_bit() {
    // A gentle, uniform flow: every particle has the same criteria.
    let (block, seen) = run(config(TimeSteps::Block, true), |_| 1.0, 1.0, 12);
    assert_eq!(seen.len(), 12);
    for s in &seen {
        let b = s.after[0];
        assert!(s.after.iter().all(|&x| x == b), "step {}", s.report.step);
        assert_eq!(s.report.updates, block.len() as u64, "all active");
    }
    let (kdk, _) = run(config(TimeSteps::Kdk, true), |_| 1.0, 1.0, 12);
    assert_same_bits(&block, &kdk, &["x", "vx", "u", "h", "rho"]);
}

/// Each named field of `a` and `b` bit for bit.
fn assert_same_bits(a: &Particles, b: &Particles, names: &[&str]) {
    for &name in names {
        let f = sph_core::fields::find(name).expect("a field of the table");
        let (x, y) = (f.f64(a).expect("f64"), f.f64(b).expect("f64"));
        assert!(
            x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{name} differs"
        );
    }
}

/// Every sub-step: each active particle `i` and each neighbour `j` have
/// `bin_j <= bin_i + delta` after it (wake-up) and `bin_i <= bin_j + delta`
/// for the bins `j` had before it (the cap). Returns the violations.
fn limiter_violations(seen: &[Seen], delta: f64) -> usize {
    let mut bad = 0;
    for (k, s) in seen.iter().enumerate() {
        let pairs = neighbour_pairs(s);
        for (i, j) in pairs {
            let active = k == 0 || is_active(s.ti, Bin(s.before[i] as u8));
            if !active {
                continue;
            }
            if s.after[j] > s.after[i] + delta || (k > 0 && s.after[i] > s.before[j] + delta) {
                bad += 1;
            }
        }
    }
    bad
}

#[test]
fn the_limiter_keeps_neighbours_within_its_factor() {
    // Fixed h: the neighbours the sub-step saw are those of the h before it.
    let fixed = |limiter| {
        let mut c = config(TimeSteps::Block, limiter);
        c.scheme.fixed_h = true;
        c
    };
    let steps = 40;
    let (_, with) = run(fixed(true), blast, 1.0, steps);
    let bins_used = |s: &Seen| {
        let mut b: Vec<u64> = s.after.iter().map(|&x| x as u64).collect();
        b.sort_unstable();
        b.dedup();
        b.len()
    };
    assert!(
        with.iter().any(|s| bins_used(s) >= 3),
        "a blast spreads over bins"
    );
    assert_eq!(limiter_violations(&with, 2.0), 0);
    // Without the limiter the cold gas sleeps through the blast's arrival.
    let (_, without) = run(fixed(false), blast, 1.0, steps);
    assert!(limiter_violations(&without, 2.0) > 0);
}

#[test]
fn block_steps_do_not_depend_on_the_thread_count() {
    let go = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(config(TimeSteps::Block, true), blast, 1.0, 25).0)
    };
    assert_same_bits(&go(1), &go(2), &["x", "vx", "u", "rho", "bin"]);
}

#[test]
fn the_start_ramp_holds_a_blast_at_most_the_limiters_factor_down() {
    // The first sub-step of a blast from rest, with the ramp from dt0
    // (the default) and without it (`FirstStep::Criteria`).
    let mut ramp = config(TimeSteps::Block, true);
    ramp.timestep.first_step = FirstStep::Ramp;
    let (_, with) = run(ramp, blast, 1.0, 1);
    let (_, without) = run(config(TimeSteps::Block, true), blast, 1.0, 1);
    let (with, without) = (&with[0].after, &without[0].after);
    // Never longer than the criteria's bin, never more than the
    // limiter's factor (two bins) below it.
    for (i, (&r, &c)) in with.iter().zip(without).enumerate() {
        assert!(r <= c && r >= c - 2.0, "particle {i}: bin {r} against {c}");
    }
    // The hot centre is held two bins down (the ramp's step from dt0 =
    // 1e-4 is far below its criteria); the bins still spread.
    let (centre, corner) = (with.iter().cloned().fold(f64::INFINITY, f64::min), with[0]);
    let hot_free = without.iter().cloned().fold(f64::INFINITY, f64::min);
    assert_eq!(centre, hot_free - 2.0, "the ramp binds at the centre");
    assert!(corner > centre + 2.0, "bins {centre} to {corner}");
}

/// A change to a preset.
type Tweak = fn(&mut Scheme);

/// Every preset, and each with its viscosity switched the other way, with
/// AV cleaning and with the Balsara limiter, runs block steps on the
/// blast with its energy kept. A scheme computes fields it does not hold
/// (cleaning or Balsara with one constant alpha computes div v); those
/// stay with the stages, and the particles pass their own checks.
/// The energy is taken where it is defined, at the first synchronisation
/// point (t = 0.1, the longest step; bins 5 apart, 15 to 29 sub-steps)
/// with every step closed: measured 2026-12-07, 3.6e-4 to 2.4e-3 (`ve-ac`;
/// conduction is exchanged as impulses: before, 5e-3 to 4e-2 with it),
/// so 5e-3 bounds them all. Until 2026-12-07 this test took the sums of
/// the eighth sub-step, over velocities predicted from each step's start
/// (up to 2.8e-3; closing the active particles' steps there moves them to
/// 5.1e-3, a mix of closed and predicted velocities that measures neither).
/// "Nothing moved" fails a frozen run (docs/block-timesteps.md).
#[test]
fn every_preset_and_variant_runs_block_steps() {
    let variants: [(&str, Tweak); 4] = [
        ("as is", |_| {}),
        ("switches flipped", |s| {
            let on = s.switches().is_none();
            s.set_switches(on);
        }),
        ("cleaning, constant alpha", |s| {
            s.av_cleaning = true;
            s.set_switches(false);
        }),
        ("Balsara, constant alpha", |s| {
            s.balsara = true;
            s.set_switches(false);
        }),
    ];
    for (name, preset, _) in PRESETS {
        for (variant, tweak) in variants {
            let mut scheme = preset;
            tweak(&mut scheme);
            // Every variant is a valid scheme: none is skipped.
            if let Err(e) = scheme.validate() {
                panic!("{name} ({variant}): {e}");
            }
            let mut c = config(TimeSteps::Block, true);
            c.scheme = scheme;
            // Pressure-energy volumes need u > 0 everywhere: the blast has it.
            let (p, drift, spread) = run_to_sync(c, blast, 0.1);
            assert!(spread >= 5.0, "{name} ({variant}): bins spread {spread}");
            assert!(
                drift.abs() < 5e-3,
                "{name} ({variant}): energy drift {drift:e}"
            );
            assert!(
                p.vx.iter().any(|&v| v != 0.0),
                "{name} ({variant}): nothing moved"
            );
        }
    }
}
