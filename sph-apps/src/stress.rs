//! `sphexa stress`: runs built to break the solver, each with a pass/fail
//! verdict and its figures (`stress.json` and a terminal table).
//!
//! Every scenario builds its own initial state here (from a case's set-up,
//! modified, or from scratch), runs it in this process with the run's
//! watch on ([`crate::watch`]: warnings recorded, not strict), and judges
//! the outcome. A run fails on an error of the solver (NaN, negative
//! internal energy, a stuck h iteration, a singular IAD matrix: each names
//! the particle, its position and the step), on a recorded violation of a
//! conserved quantity, or on the scenario's own criterion. The extreme
//! inputs pass when the bad particle is named (by a refusal or a recorded
//! violation) and nothing non-finite is written.

use crate::cases::{self, Scene};
use crate::rng::SplitMix64;
use crate::simulation::{Progress, Stop};
use crate::{AppError, Simulation, Summary};
use serde::Serialize;
use sph_core::{HydroConfig, TimeSteps};
use sph_kernels::KernelChoice;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The verdict and figures of one scenario.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Scenario name.
    pub name: String,
    /// What it does.
    pub what: String,
    /// Whether it passed.
    pub pass: bool,
    /// Why it passed or failed (the solver's error names the particle and
    /// the step).
    pub note: String,
    /// Its figures (steps, drifts, the scenario's own measures).
    pub figures: BTreeMap<String, f64>,
    /// Wall-clock seconds.
    pub wall_s: f64,
}

/// The suite's options.
#[derive(Debug, Clone)]
pub struct Options {
    /// The short suite (CI, under 5 minutes on 2 cores).
    pub quick: bool,
    /// Folder for the runs' outputs and `stress.json`.
    pub out: PathBuf,
    /// Print each scenario's line as it finishes.
    pub verbose: bool,
    /// How the particles share time steps in every scenario.
    pub time_steps: TimeSteps,
}

/// The end of a block-step time line for a scenario that stops after a
/// number of (sub-)steps.
const STEPS_HORIZON: f64 = 1e6;

/// The numerical controls of a scenario.
fn config(ng0: usize, ngmax: usize, courant: f64) -> HydroConfig {
    let mut c = HydroConfig::default();
    c.neighbors.ng0 = ng0;
    c.neighbors.ngmax = ngmax;
    c.timestep.k_courant = courant;
    c
}

/// A case's scene with `config`.
fn case_scene(case: &str, side: usize, config: HydroConfig) -> Result<Scene, AppError> {
    cases::lookup(case)?.setup(side, config)
}

/// A periodic unit box at rest, uniform density 1 and pressure `p0`
/// (gamma = 5/3): the Sedov lattice with its blast removed.
fn uniform_box(side: usize, p0: f64, config: HydroConfig) -> Result<Scene, AppError> {
    let mut s = case_scene("sedov", side, config)?;
    s.particles.u.fill(1.5 * p0);
    s.reference = None;
    s.case = "uniform-box";
    Ok(s)
}

/// Runs `scene` to `stop` with `kernel` and the time steps of `o` into
/// `dir` (`--steps` counts sub-steps under block time steps); the summary
/// or the error, and the wall time.
fn run(
    o: &Options,
    mut scene: Scene,
    kernel: KernelChoice,
    stop: Stop,
    dir: &Path,
) -> (Result<Summary, AppError>, f64) {
    scene.config.time_steps = o.time_steps;
    let start = Instant::now();
    let result = kernel
        .fast()
        .map_err(AppError::from)
        .and_then(|k| Simulation::new(scene, k, kernel.to_string()))
        .and_then(|mut sim| {
            // A block-step line needs an end: far beyond any scenario's
            // steps (each synchronisation point may start a new line).
            sim.set_time_line_end(STEPS_HORIZON);
            sim.run(stop, dir, Progress::Quiet)
        });
    (result, start.elapsed().as_secs_f64())
}

/// The common judgement: an error fails (its message is the note), a
/// recorded violation fails, non-finite figures fail.
fn judge(name: &str, what: &str, result: Result<Summary, AppError>, wall_s: f64) -> Outcome {
    let mut o = Outcome {
        name: name.into(),
        what: what.into(),
        pass: false,
        note: String::new(),
        figures: BTreeMap::new(),
        wall_s,
    };
    match result {
        Err(e) => o.note = e.to_string(),
        Ok(s) => {
            o.figures.insert("steps".into(), s.steps as f64);
            o.figures
                .insert("particle_updates".into(), s.particle_updates as f64);
            o.figures.insert("t_end".into(), s.t_end);
            o.figures.insert("energy_drift".into(), s.energy_rel_drift);
            o.figures
                .insert("momentum_drift".into(), s.momentum_rel_drift);
            o.figures.insert("peak_density".into(), s.peak_density);
            o.figures
                .insert("min_pair_distance".into(), s.min_pair_distance);
            for (limit, steps) in &s.dt_limits {
                o.figures.insert(format!("dt_by_{limit}"), *steps as f64);
            }
            if let Some(l1) = s.l1 {
                o.figures.insert("l1_rho".into(), l1.rho);
                o.figures.insert("l1_p".into(), l1.p);
            }
            if let Some(v) = s.watch.violations.first() {
                o.note = format!("{v}");
            } else if o.figures.values().any(|v| !v.is_finite()) {
                o.note = "a non-finite figure".into();
            } else {
                o.pass = true;
                o.note = "ran clean".into();
            }
        }
    }
    o
}

/// Smallest pair distance of the particles of `scene` (periodic minimum
/// image; all pairs, for small scenes).
fn min_pair_distance(scene: &Scene) -> f64 {
    let p = &scene.particles;
    let len = scene.bbox.lengths();
    let mut best = f64::INFINITY;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d: f64 = [p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j]]
                .iter()
                .enumerate()
                .map(|(k, &d)| {
                    let d = if scene.bbox.is_periodic(k) {
                        d - len[k] * (d / len[k]).round()
                    } else {
                        d
                    };
                    d * d
                })
                .sum();
            best = best.min(d);
        }
    }
    best.sqrt()
}

/// The rms speed of each step, from `conserved.csv` (E_kin) and the mass.
fn v_rms_history(dir: &Path, mass: f64) -> Vec<f64> {
    std::fs::read_to_string(dir.join("conserved.csv"))
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(3)?.parse::<f64>().ok())
        .map(|e| (2.0 * e / mass).sqrt())
        .collect()
}

/// The columns of `conserved.csv` at every step.
fn conserved_rows(dir: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(dir.join("conserved.csv"))
        .unwrap_or_default()
        .lines()
        .skip(1)
        .map(|l| l.split(',').filter_map(|c| c.parse().ok()).collect())
        .collect()
}

/// Noisy lattice relaxing under uniform pressure: the rms speed the noise
/// sets off must decay (final below half its peak) and the particles must
/// not clump (closest pair at the end at least 0.8 of the initial one).
fn noisy_lattice(o: &Options, noise: f64) -> Result<Outcome, AppError> {
    let (side, steps) = if o.quick { (10, 150) } else { (16, 400) };
    let mut s = uniform_box(side, 1.0, config(100, 150, 0.2))?;
    let dx = 1.0 / side as f64;
    let mut rng = SplitMix64(7 + (noise * 100.0) as u64);
    let p = &mut s.particles;
    for i in 0..p.len() {
        for c in [&mut p.x, &mut p.y, &mut p.z] {
            let mut v = c[i] + noise * dx * (2.0 * rng.uniform() - 1.0);
            v -= (v + 0.5).div_euclid(1.0);
            c[i] = v;
        }
    }
    s.case = "noisy-lattice";
    let mass: f64 = s.particles.m.iter().sum();
    let d0 = min_pair_distance(&s);
    let name = format!("noisy-lattice-{:.0}%", noise * 100.0);
    let dir = o.out.join(&name);
    let (r, wall) = run(o, s, KernelChoice::default(), Stop::Steps(steps), &dir);
    let what = format!(
        "{side}^3 periodic lattice, displacements up to {:.0}% of the spacing, uniform P = 1, {steps} steps",
        noise * 100.0
    );
    let mut out = judge(&name, &what, r, wall);
    let v = v_rms_history(&dir, mass);
    let peak = v.iter().copied().fold(0.0, f64::max);
    let last = v.last().copied().unwrap_or(f64::NAN);
    out.figures.insert("v_rms_peak".into(), peak);
    out.figures.insert("v_rms_end".into(), last);
    out.figures.insert("min_pair_distance_0".into(), d0);
    if out.pass {
        let d1 = out.figures["min_pair_distance"];
        if last >= 0.5 * peak || last.is_nan() {
            out.pass = false;
            out.note = format!("v_rms did not decay: {last:.3e} at the end against a peak {peak:.3e} (needs < 1/2)");
        } else if d1 < 0.8 * d0 {
            out.pass = false;
            out.note = format!(
                "clumping: closest pair {d1:.3e} at the end against {d0:.3e} at the start (needs >= 0.8x)"
            );
        } else {
            out.note = format!("v_rms {peak:.2e} -> {last:.2e}; closest pair {d0:.3e} -> {d1:.3e}");
        }
    }
    Ok(out)
}

/// A case at one Courant factor: passes when it runs clean (watch: energy
/// drift within 1e-2).
fn courant(o: &Options, case: &str, k: f64) -> Result<Outcome, AppError> {
    let (side, t) = match (case, o.quick) {
        ("sedov", true) => (12, 0.03),
        ("sedov", false) => (20, 0.05),
        (_, true) => (16, 0.1),
        (_, false) => (24, 0.3),
    };
    let s = case_scene(case, side, config(100, 150, k))?;
    let name = format!("courant-{case}-{k}");
    let (r, wall) = run(
        o,
        s,
        KernelChoice::default(),
        Stop::Time(t),
        &o.out.join(&name),
    );
    let what = format!("{case} -n {side} to t = {t} at Courant factor {k}");
    let mut out = judge(&name, &what, r, wall);
    out.figures.insert("courant".into(), k);
    if out.pass {
        let f = |n: &str| out.figures.get(n).copied().unwrap_or(0.0);
        out.note = format!(
            "steps set by courant {} / divergence {} / growth {}{}",
            f("dt_by_courant"),
            f("dt_by_divergence"),
            f("dt_by_growth"),
            out.figures
                .get("l1_rho")
                .map_or(String::new(), |l| format!("; L1 rho {l:.4}"))
        );
    }
    Ok(out)
}

/// Sod with a pressure ratio of 1e5 (the thin gas at P = 1e-5): must run
/// to t = 0.1 without a failure or a drift past its bound.
fn strong_sod(o: &Options) -> Result<Outcome, AppError> {
    let side = if o.quick { 40 } else { 80 };
    let mut s = case_scene("sod", side, config(100, 150, 0.2))?;
    let h_min = s.particles.h.iter().copied().fold(f64::INFINITY, f64::min);
    for i in 0..s.particles.len() {
        // The thin gas has twice the dense spacing and smoothing length.
        if s.particles.h[i] > 1.5 * h_min {
            s.particles.u[i] *= 1e-4;
        }
    }
    s.reference = None;
    s.case = "strong-sod";
    let name = "strong-sod-1e5".to_string();
    let (r, wall) = run(
        o,
        s,
        KernelChoice::default(),
        Stop::Time(0.1),
        &o.out.join(&name),
    );
    let what = format!("sod -n {side}, thin gas P = 1e-5 (ratio 1e5), to t = 0.1");
    Ok(judge(&name, &what, r, wall))
}

/// Sedov with a given kernel and neighbour count.
fn kernel_case(o: &Options, kernel: &str, ng0: usize) -> Result<Outcome, AppError> {
    let (side, t) = if o.quick { (12, 0.03) } else { (20, 0.05) };
    let ngmax = ng0 + ng0 / 2;
    let s = case_scene("sedov", side, config(ng0, ngmax, 0.2))?;
    let k: KernelChoice = kernel
        .parse()
        .map_err(|e: sph_kernels::KernelError| AppError::Usage(e.to_string()))?;
    let name = format!("sedov-{}-ng{ng0}", kernel.replace(':', ""));
    let (r, wall) = run(o, s, k, Stop::Time(t), &o.out.join(&name));
    let what = format!("sedov -n {side} to t = {t}, kernel {kernel}, ng0 {ng0}, ngmax {ngmax}");
    Ok(judge(&name, &what, r, wall))
}

/// A dense clump (smoothing lengths 100x smaller: density 1e6 times the
/// medium's, equal particle masses) in pressure balance in a thin
/// periodic medium, 100 steps in the quick suite too: before the energy
/// time-step criterion a clump particle's u turned negative at step 86.
fn clump(o: &Options) -> Result<Outcome, AppError> {
    let (side, k, steps) = (16, 4, 100);
    let base = uniform_box(side, 1.0, config(100, 150, 0.2))?;
    let dx = 1.0 / side as f64;
    let dc = dx / 100.0;
    let nc = k * k * k;
    let n = base.particles.len() + nc;
    let mut p = sph_core::Particles::new(n, base.particles.fields());
    let m = base.particles.m[0];
    let h_bg = base.particles.h[0];
    for i in 0..base.particles.len() {
        p.x[i] = base.particles.x[i];
        p.y[i] = base.particles.y[i];
        p.z[i] = base.particles.z[i];
        p.m[i] = m;
        p.h[i] = h_bg;
        p.u[i] = base.particles.u[i];
        p.id[i] = i as u64;
    }
    // The clump sits between lattice sites (which are at (j + 1/2) dx).
    for c in 0..nc {
        let i = base.particles.len() + c;
        let q = [c % k, c / k % k, c / (k * k)];
        let pos = q.map(|a| (a as f64 - 0.5 * (k as f64 - 1.0)) * dc);
        (p.x[i], p.y[i], p.z[i]) = (pos[0], pos[1], pos[2]);
        p.m[i] = m;
        p.h[i] = h_bg / 100.0;
        p.u[i] = base.particles.u[0] * 1e-6;
        p.id[i] = i as u64;
    }
    let s = Scene {
        case: "clump",
        total: n,
        particles: p,
        ..base
    };
    let name = "h-spread-100x".to_string();
    let (r, wall) = run(
        o,
        s,
        KernelChoice::default(),
        Stop::Steps(steps),
        &o.out.join(&name),
    );
    let what = format!(
        "{side}^3 periodic medium (rho 1, P 1) with a {k}^3 clump of the same masses at 1/100 the spacing (rho 1e6, h 100x smaller, pressure balance), {steps} steps"
    );
    Ok(judge(&name, &what, r, wall))
}

/// A Mach 10 blob (the wind-shock set-up at a higher Mach number): a
/// cloud of radius 0.1 and density 10 at rest in a periodic unit box of
/// gas at density 1 streaming along x at 10 times its sound speed, in
/// pressure balance (P = 1); equal particle masses, the cloud's lattice
/// 10^(1/3) times finer.
fn mach10_blob(o: &Options) -> Result<Outcome, AppError> {
    // The wind crosses the cloud's radius in 0.0077 and the box in 0.077.
    let (side, t_end) = if o.quick { (12, 0.02) } else { (20, 0.08) };
    let base = uniform_box(side, 1.0, config(100, 150, 0.2))?;
    let radius = 0.1;
    let gamma = 5.0f64 / 3.0;
    let c = (gamma * 1.0 / 1.0).sqrt();
    let wind = 10.0 * c;
    let bp = &base.particles;
    let outside: Vec<usize> = (0..bp.len())
        .filter(|&i| (bp.x[i].powi(2) + bp.y[i].powi(2) + bp.z[i].powi(2)).sqrt() >= radius)
        .collect();
    let dx = 1.0 / side as f64;
    let dc = dx / 10f64.cbrt();
    let k = (2.0 * radius / dc).ceil() as usize + 1;
    let cloud: Vec<[f64; 3]> = (0..k * k * k)
        .map(|c| [c % k, c / k % k, c / (k * k)].map(|a| (a as f64 - 0.5 * (k as f64 - 1.0)) * dc))
        .filter(|q| (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() < radius)
        .collect();
    let n = outside.len() + cloud.len();
    let mut p = sph_core::Particles::new(n, bp.fields());
    let (m, u_bg, h_bg) = (bp.m[0], bp.u[0], bp.h[0]);
    for (k, &i) in outside.iter().enumerate() {
        (p.x[k], p.y[k], p.z[k]) = (bp.x[i], bp.y[i], bp.z[i]);
        p.vx[k] = wind;
        (p.m[k], p.h[k], p.u[k]) = (m, h_bg, u_bg);
    }
    for (k, q) in cloud.iter().enumerate() {
        let i = outside.len() + k;
        (p.x[i], p.y[i], p.z[i]) = (q[0], q[1], q[2]);
        (p.m[i], p.h[i], p.u[i]) = (m, h_bg * dc / dx, u_bg / 10.0);
    }
    for i in 0..n {
        p.id[i] = i as u64;
    }
    let s = Scene {
        case: "mach10-blob",
        total: n,
        particles: p,
        ..base
    };
    let name = "mach10-blob".to_string();
    let (r, wall) = run(
        o,
        s,
        KernelChoice::default(),
        Stop::Time(t_end),
        &o.out.join(&name),
    );
    let what = format!(
        "cloud r = 0.1, rho 10 at rest in a {side}^3 periodic wind, rho 1, P 1, v_x = 10 c = {wind:.2}; {n} particles, to t = {t_end}"
    );
    Ok(judge(&name, &what, r, wall))
}

/// A small periodic box at rest for many steps: energy and momentum drift.
fn at_rest(o: &Options) -> Result<Outcome, AppError> {
    let (side, steps) = if o.quick { (8, 2000) } else { (8, 10_000) };
    let s = uniform_box(side, 1.0, config(100, 150, 0.2))?;
    let name = "box-at-rest".to_string();
    let dir = o.out.join(&name);
    let (r, wall) = run(o, s, KernelChoice::default(), Stop::Steps(steps), &dir);
    let what = format!("{side}^3 periodic lattice at rest, uniform P = 1, {steps} steps");
    let mut out = judge(&name, &what, r, wall);
    // Momentum against M c (mass 1, sound speed sqrt(5/3)): the velocities
    // themselves are round-off, so the summary's |dp| / sum m|v| is not a
    // measure here.
    let rows = conserved_rows(&dir);
    let p_max = rows
        .iter()
        .map(|r| {
            r.get(7..10)
                .map_or(f64::NAN, |p| p.iter().map(|x| x * x).sum::<f64>().sqrt())
        })
        .fold(0.0, f64::max);
    let v_max = rows
        .iter()
        .map(|r| (2.0 * r.get(3).copied().unwrap_or(f64::NAN)).sqrt())
        .fold(0.0, f64::max);
    let c = (5.0f64 / 3.0).sqrt();
    out.figures.insert("momentum_over_Mc_max".into(), p_max / c);
    out.figures.insert("v_rms_over_c_max".into(), v_max / c);
    if out.pass {
        let e = out.figures["energy_drift"];
        out.note = format!(
            "energy drift {e:.2e}, |p| / (M c) at most {:.2e}, v_rms / c at most {:.2e}",
            p_max / c,
            v_max / c
        );
    }
    Ok(out)
}

/// Extreme inputs: the run passes when nothing non-finite is written and
/// a bad particle is named (a refusal, a solver error or a recorded
/// violation naming its id), or when it runs clean.
fn extreme(o: &Options, which: &str) -> Result<Outcome, AppError> {
    let side = 8;
    let mut s = uniform_box(side, 1.0, config(100, 150, 0.2))?;
    let target = 100usize;
    let what = match which {
        "coincident" => {
            // Particle 100 on top of particle 101.
            s.particles.x[target] = s.particles.x[target + 1];
            s.particles.y[target] = s.particles.y[target + 1];
            s.particles.z[target] = s.particles.z[target + 1];
            "8^3 box at rest, particle 100 on top of particle 101, 50 steps"
        }
        "zero-mass" => {
            s.particles.m[target] = 0.0;
            "8^3 box at rest, particle 100 with mass 0, 50 steps"
        }
        _ => {
            s.particles.u.fill(0.0);
            "8^3 box at rest, u = 0 everywhere (P = 0, c = 0), 50 steps"
        }
    };
    let name = format!("extreme-{which}");
    let dir = o.out.join(&name);
    let (r, wall) = run(o, s, KernelChoice::default(), Stop::Steps(50), &dir);
    let refused = match &r {
        Err(e) => Some(e.to_string()),
        Ok(_) => None,
    };
    let mut out = judge(&name, what, r, wall);
    if which == "coincident" && out.pass {
        out.note = format!(
            "ran clean; closest pair at the end {:.3e} (0: the pair never separates, W' = 0 at r = 0)",
            out.figures["min_pair_distance"]
        );
    }
    let named = out.note.contains(&format!("id {target}"));
    match (which, refused) {
        (_, Some(msg)) => {
            out.pass = msg.contains("particle id") || msg.contains("id ");
            out.note = format!("stopped: {msg}");
        }
        ("zero-mass", None) => {
            out.pass = named && out.figures.values().all(|v| v.is_finite());
            out.note = format!("recorded: {}", out.note);
        }
        ("u-zero", None) => {
            // E = 0 at the start: the relative drift is 0/0; what must hold
            // is that nothing moves and nothing is non-finite.
            let rows = conserved_rows(&dir);
            let still = !rows.is_empty()
                && rows
                    .iter()
                    .all(|r| r.len() == 16 && r[3..7].iter().all(|e| *e == 0.0));
            out.figures.remove("energy_drift");
            out.pass = still && out.figures.values().all(|v| v.is_finite());
            out.note = if still {
                "P = 0: nothing moves, every energy exactly 0 at every step".into()
            } else {
                format!("energies not all 0 or not finite: {}", out.note)
            };
        }
        _ => {}
    }
    Ok(out)
}

/// Runs the suite (`quick`: the CI subset) and writes `stress.json` into
/// `out`.
///
/// # Errors
/// A scenario that cannot be set up, or `stress.json` not written.
pub fn run_suite(o: &Options) -> Result<Vec<Outcome>, AppError> {
    std::fs::create_dir_all(&o.out).map_err(|e| AppError::io(&o.out, e))?;
    type Job<'a> = Box<dyn Fn() -> Result<Outcome, AppError> + 'a>;
    let mut jobs: Vec<Job<'_>> = vec![
        Box::new(|| noisy_lattice(o, 0.1)),
        Box::new(|| noisy_lattice(o, 0.3)),
    ];
    let courants: &[f64] = if o.quick {
        &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    } else {
        &[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0]
    };
    for case in ["sedov", "gresho"] {
        for &k in courants {
            jobs.push(Box::new(move || courant(o, case, k)));
        }
    }
    jobs.push(Box::new(|| mach10_blob(o)));
    jobs.push(Box::new(|| strong_sod(o)));
    jobs.push(Box::new(|| kernel_case(o, "sinc:10", 100)));
    jobs.push(Box::new(|| kernel_case(o, "sinc:6", 50)));
    jobs.push(Box::new(|| kernel_case(o, "sinc:6", 30)));
    jobs.push(Box::new(|| clump(o)));
    jobs.push(Box::new(|| at_rest(o)));
    for which in ["coincident", "zero-mass", "u-zero"] {
        jobs.push(Box::new(move || extreme(o, which)));
    }
    let mut outcomes = Vec::new();
    for job in jobs {
        let out = job()?;
        if o.verbose {
            eprintln!(
                "{} {:<24} {:>7.1} s  {}",
                if out.pass { "pass" } else { "FAIL" },
                out.name,
                out.wall_s,
                out.note
            );
        }
        outcomes.push(out);
    }
    let path = o.out.join("stress.json");
    let json = serde_json::to_string_pretty(&outcomes).expect("outcomes serialise");
    std::fs::write(&path, json + "\n").map_err(|e| AppError::io(&path, e))?;
    Ok(outcomes)
}

/// The terminal table of `outcomes`.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut t = format!(
        "{:<24} {:<5} {:>7} {:>10} {:>10}  note\n",
        "scenario", "", "steps", "E drift", "wall s"
    );
    for o in outcomes {
        let f = |k: &str| o.figures.get(k).copied();
        t += &format!(
            "{:<24} {:<5} {:>7} {:>10} {:>10.1}  {}\n",
            o.name,
            if o.pass { "pass" } else { "FAIL" },
            f("steps").map_or("-".into(), |s| format!("{s}")),
            f("energy_drift").map_or("-".into(), |e| format!("{e:.2e}")),
            o.wall_s,
            o.note
        );
    }
    t
}
