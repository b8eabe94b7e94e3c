//! Rank-count independence (built only with `--features mpi`; run by
//! `cargo test -p sph-validation --features mpi --test distributed`).
//!
//! Without arguments this binary is the launcher: for every case it runs
//! itself as a child once serially with 1 thread (the reference), serially
//! with 2 threads, and under `mpirun -n 2` and `-n 4` with 1 thread per
//! rank, each child writing `conserved.csv` and `particles.csv` (the full
//! final state sorted by id, every value in exact round-trip decimals).
//! Every run must give byte-identical files. The `drift` case moves a
//! uniform gas across the periodic boundaries so that particles migrate
//! between ranks every few steps: no particle may be lost or duplicated,
//! and mass, momentum and energy must be conserved. `sedov-ve` is Sedov
//! with the `ve` preset (volume elements, switches: halo refreshes of X,
//! k, div v and alpha). `SPH_DISTRIBUTED_ONLY=sedov-ve,drift` runs only
//! the cases named.
//!
//! The runs write under the target directory (`target/tmp/distributed`,
//! removed when every check passes, kept for inspection otherwise) and
//! take their glasses from `target/tmp/glass` ([`sph_validation::layout`]),
//! whatever `HOME` is; `mpirun` and its options come from
//! [`sph_comm::launch`].

use sph_apps::cases::{self, Scene};
use sph_apps::simulation::{Progress, Stop};
use sph_apps::Simulation;
use sph_comm::launch::Launcher;
use sph_comm::{Communicator, MpiComm};
use sph_kernels::{FastKernel, KernelChoice};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Particles per side and steps of each run: (case, side, steps). Every
/// registered case runs (with [`DEFAULT_SIZE`] unless listed here), then
/// the test-only `drift` case.
const SIZES: [(&str, usize, u64); 13] = [
    ("sedov", 24, 20),
    // Its box is 0.25 across: 32 per unit length gives the kernel room.
    ("wind-shock", 32, 20),
    ("sedov-ve", 24, 20),
    // Block time steps (the paper's scheme): 30 sub-steps over bins 45-49
    // of a line to 0.05.
    ("sedov-block", 24, 30),
    // Block steps with switches, volume elements and conduction (`best`;
    // Sedov's own, `gas`, runs block steps in `sedov`).
    ("sedov-best-block", 24, 30),
    // Block steps with self-gravity: 30 sub-steps of a line to t = 1.
    ("evrard-block", 16, 30),
    // Block steps in one-step lines (switches, cleaning, IAD).
    ("kelvin-helmholtz-block", 16, 30),
    // Block steps with pressure-energy volumes, the two gases in bins.
    ("isobaric-cube-block", 10, 30),
    // Block steps with driving: kept stirring accelerations migrate, the
    // driving's net force and work are exact sums (from rest every
    // particle takes the same step: sub-steps where part of a stirred gas
    // is active are checked across ranks in sph-core/tests/integration/stirred.rs).
    ("turbulence-block", 16, 30),
    ("square-patch", 20, 20),
    ("noh", 20, 20),
    ("drift", 16, 30),
    ("evrard", 16, 30),
];
/// Side and steps of a registered case missing from [`SIZES`].
const DEFAULT_SIZE: (usize, u64) = (16, 20);

/// The runs: every registered case, then `drift`, `sedov-ve` and
/// `sedov-block`, `sedov-best-block`, `evrard-block`,
/// `kelvin-helmholtz-block`, `isobaric-cube-block` and `turbulence-block`
/// (block time steps: wake-ups brought to their owners, halos refreshed
/// between syncs, gravity for the active particles on a drifted tree, the
/// choice of each new time line, driving), with
/// their sizes (only those in `SPH_DISTRIBUTED_ONLY`, when set).
fn runs() -> Vec<(&'static str, usize, u64)> {
    let only = std::env::var("SPH_DISTRIBUTED_ONLY").ok();
    cases::names()
        .into_iter()
        .chain([
            "drift",
            "sedov-ve",
            "sedov-block",
            "sedov-best-block",
            "evrard-block",
            "kelvin-helmholtz-block",
            "isobaric-cube-block",
            "turbulence-block",
        ])
        .filter(|case| {
            only.as_ref()
                .is_none_or(|o| o.split(',').any(|c| c == *case))
        })
        .map(|case| {
            let (side, steps) = SIZES
                .iter()
                .find(|c| c.0 == case)
                .map_or(DEFAULT_SIZE, |c| (c.1, c.2));
            (case, side, steps)
        })
        .collect()
}

/// Cases that cannot be bit-identical across rank counts: self-gravity
/// applies remote ranks' nodes as multipoles accepted for the receiving
/// rank's whole domain, so the tree approximation (not the physics)
/// depends on the decomposition. Their outputs are compared to a bound.
fn approximate(case: &str) -> bool {
    case == "evrard-block" || cases::find(case).is_some_and(|c| c.physics().softening.is_some())
}
const TIMEOUT: Duration = Duration::from_secs(600);

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--child") {
        let (mode, case, out, threads) = (&args[i + 1], &args[i + 2], &args[i + 3], &args[i + 4]);
        child(
            mode,
            case,
            Path::new(out),
            threads.parse().expect("threads"),
        );
    } else {
        launcher();
    }
}

/// `scheme` in place of Sedov's own (`gas`).
fn preset(scheme: sph_core::Scheme) -> cases::SchemeOverrides {
    cases::SchemeOverrides {
        preset: Some(scheme),
        ..Default::default()
    }
}

fn scene(case: &str) -> Scene {
    let (_, side, _) = runs()
        .into_iter()
        .find(|c| c.0 == case)
        .expect("known case");
    if case == "drift" {
        // Uniform warm gas moving as a whole through the periodic box.
        let mut s = sph_validation::scene_with("sedov", side, &preset(sph_core::Scheme::PAPER));
        let p = &mut s.particles;
        for i in 0..p.len() {
            (p.vx[i], p.vy[i], p.vz[i]) = (3.0, -2.0, 1.0);
            p.u[i] = 1.0;
        }
        s.dt0 = 2e-3;
        s.reference = None;
        return s;
    }
    if case == "sedov-block" || case == "sedov-best-block" {
        let scheme = if case == "sedov-best-block" {
            sph_core::Scheme::BEST
        } else {
            sph_core::Scheme::PAPER
        };
        let mut s = sph_validation::scene_with("sedov", side, &preset(scheme));
        s.config.time_steps = sph_core::TimeSteps::Block;
        s.config.timestep.first_step = sph_core::timestep::FirstStep::Criteria;
        return s;
    }
    if let Some(base) = ["evrard", "kelvin-helmholtz", "isobaric-cube", "turbulence"]
        .into_iter()
        .find(|b| case.strip_suffix("-block") == Some(*b))
    {
        let mut s = sph_validation::scene(base, side);
        s.config.time_steps = sph_core::TimeSteps::Block;
        return s;
    }
    if case == "sedov-ve" {
        return sph_validation::scene_with("sedov", side, &preset(sph_core::Scheme::VE));
    }
    // Each case with its own scheme, applied by its set-up (noh: kernel
    // gradients and viscosity switches, whose halo refreshes of div v and
    // alpha this exercises).
    sph_validation::scene(case, side)
}

/// Where the time line of a block-step run ends: Sedov's end time,
/// Evrard's bounce, the other cases' end times.
fn line_end(case: &str) -> f64 {
    match case {
        "evrard-block" | "isobaric-cube-block" => 1.0,
        "kelvin-helmholtz-block" => 1.5,
        "turbulence-block" => 10.0,
        _ => 0.05,
    }
}

fn child(mode: &str, case: &str, out: &Path, threads: usize) {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("thread pool");
    let steps = runs().into_iter().find(|c| c.0 == case).expect("case").2;
    let kernel: FastKernel = KernelChoice::default().fast().expect("kernel");
    let name = KernelChoice::default().to_string();
    let mut rank = 0;
    let summary = if mode == "mpi" {
        let comm = MpiComm::init().expect("MPI");
        rank = comm.rank();
        let mut sim = Simulation::with_comm(scene(case), kernel, name, comm).expect("set-up");
        sim.set_write_particles(true);
        sim.set_time_line_end(line_end(case));
        // The non-generic runs: the solver is not compiled again here.
        sim.run_mpi(Stop::Steps(steps), out, Progress::Quiet)
    } else {
        let mut sim = Simulation::new(scene(case), kernel, name).expect("set-up");
        sim.set_write_particles(true);
        sim.set_time_line_end(line_end(case));
        sim.run_serial(Stop::Steps(steps), out, Progress::Quiet)
    };
    match summary {
        Ok(_) if rank > 0 => {}
        Ok(s) => println!(
            "ranks {} halo ratio {:.3} owned {}..{}",
            s.ranks, s.domain.halo_ratio_mean, s.domain.owned_min, s.domain.owned_max
        ),
        Err(e) => {
            eprintln!("run failed: {e}");
            std::process::exit(1);
        }
    }
}

fn launcher() {
    let exe = std::env::current_exe().expect("own path");
    let mpirun = Launcher::detect().unwrap_or_else(|e| panic!("{e}"));
    let root = sph_validation::scratch("distributed");
    let mut failures = Vec::new();
    for (case, side, steps) in runs() {
        // (label, ranks, threads)
        let runs = [
            ("serial-1t", 0, 1),
            ("serial-2t", 0, 2),
            ("mpi-2", 2, 1),
            ("mpi-4", 4, 1),
        ];
        let mut dirs: Vec<(String, PathBuf)> = Vec::new();
        for (label, ranks, threads) in runs {
            let dir = root.join(case).join(label);
            let mut cmd = if ranks == 0 {
                let mut c = Command::new(&exe);
                c.args(["--child", "serial", case]);
                c
            } else {
                let mut c = mpirun.command(ranks);
                c.arg(&exe).args(["--child", "mpi", case]);
                c
            };
            cmd.arg(&dir).arg(threads.to_string());
            cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
            let start = Instant::now();
            let (out, err, ok) = wait_with_timeout(cmd.spawn().expect("spawn"), TIMEOUT);
            let out = String::from_utf8_lossy(&out);
            println!(
                "{case} {side}^3 {steps} steps {label}: {} in {:.1} s: {}",
                if ok { "ok" } else { "FAILED" },
                start.elapsed().as_secs_f64(),
                out.trim()
            );
            if !ok {
                println!("--- stderr ---\n{}", String::from_utf8_lossy(&err));
                failures.push(format!("{case} {label}: run failed"));
                continue;
            }
            dirs.push((label.to_string(), dir));
        }
        let Some((_, reference)) = dirs.first() else {
            continue;
        };
        for file in ["conserved.csv", "particles.csv"] {
            let want = std::fs::read(reference.join(file)).expect("reference output");
            for (label, dir) in &dirs[1..] {
                let got = std::fs::read(dir.join(file)).expect("output");
                if approximate(case) {
                    // Same bits within one rank (threads); across ranks the
                    // forces differ by the tree's own error (p99 <= 1e-3
                    // against direct summation), so that bounds the state.
                    // Block steps: a particle whose time-step criterion
                    // lies within that error of a power-of-two boundary
                    // can take another bin, hence another step (evrard-block
                    // at 16^3, 30 sub-steps: largest 1.15e-3 on 2 and 4
                    // ranks, 2026-12-06; 2.0e-3 before, in one particle's
                    // density, 99% of particles within 7.7e-5).
                    let bound = if label.starts_with("serial") {
                        0.0
                    } else if case == "evrard-block" {
                        5e-3
                    } else {
                        1e-3
                    };
                    let worst = max_relative_difference(&want, &got);
                    println!("{case} {label} {file}: largest relative difference {worst:.2e}");
                    if worst > bound {
                        failures.push(format!(
                            "{case}: {file} of {label} differs from serial-1t by {worst:e} (bound {bound:e})"
                        ));
                    }
                    continue;
                }
                if got != want {
                    failures.push(format!(
                        "{case}: {file} of {label} differs from serial-1t{}",
                        first_difference(&want, &got)
                    ));
                }
            }
        }
        if case == "drift" {
            if let Err(e) = check_migration(reference, side * side * side) {
                failures.push(format!("drift: {e}"));
            }
        }
    }
    if failures.is_empty() {
        std::fs::remove_dir_all(&root).ok();
        println!("distributed: all runs bit-identical (gravity cases within their bound)");
    } else {
        for f in &failures {
            println!("FAILED: {f}");
        }
        println!("the runs are kept in {}", root.display());
        std::process::exit(1);
    }
}

/// Every particle id present once, mass exact, momentum and energy kept.
fn check_migration(dir: &Path, n: usize) -> Result<(), String> {
    let text = std::fs::read_to_string(dir.join("particles.csv")).map_err(|e| e.to_string())?;
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let ids: Vec<u64> = rows.iter().map(|r| r[0] as u64).collect();
    if ids != (0..n as u64).collect::<Vec<_>>() {
        return Err(format!(
            "{} particles at the end, ids not 0..{n}",
            ids.len()
        ));
    }
    let mass: f64 = rows.iter().map(|r| r[8]).sum();
    if (mass - 1.0).abs() > 1e-12 {
        return Err(format!("total mass {mass}, expected 1"));
    }
    // The gas crossed the box: its mean displacement is at least a few spacings.
    let cons = std::fs::read_to_string(dir.join("conserved.csv")).map_err(|e| e.to_string())?;
    let rows: Vec<Vec<f64>> = cons
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    let travelled = 3.0 * last[1];
    if travelled < 4.0 / 16.0 {
        return Err(format!(
            "gas moved only {travelled} in x: too little migration"
        ));
    }
    // Columns: step, t, dt, E_kin, E_int, E_grav, E_tot, px, py, pz, ...
    for k in 7..10 {
        let rel = (last[k] - first[k]).abs() / 3.0;
        if rel > 1e-12 {
            return Err(format!("momentum component {} changed by {rel:e}", k - 7));
        }
    }
    let de = (last[6] - first[6]).abs() / first[6];
    if de > 1e-6 {
        return Err(format!("total energy changed by {de:e}"));
    }
    Ok(())
}

/// Columns compared for the approximate cases: the physical state and the
/// energies, each relative to its largest magnitude in the reference.
/// (Momenta of a gravity run are tree-force round-off, ~1e-6 of m|v|,
/// different for every decomposition; they are not compared.)
const COMPARED: [&str; 13] = [
    "t", "dt", "E_kin", "E_int", "E_grav", "E_tot", "x", "y", "z", "h", "u", "rho", "vx",
];

/// Largest `max |a - b| / max |a|` over the compared columns of two CSV
/// files of the same shape (infinite if the shapes differ).
fn max_relative_difference(a: &[u8], b: &[u8]) -> f64 {
    let parse = |t: &[u8]| -> (Vec<String>, Vec<Vec<f64>>) {
        let text = String::from_utf8_lossy(t).to_string();
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap_or("")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        (header, rows)
    };
    let ((ha, ra), (hb, rb)) = (parse(a), parse(b));
    if ha != hb || ra.len() != rb.len() || ra.iter().zip(&rb).any(|(x, y)| x.len() != y.len()) {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for (c, name) in ha.iter().enumerate() {
        if !COMPARED.contains(&name.as_str()) {
            continue;
        }
        let scale = ra.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
        let diff = ra
            .iter()
            .zip(&rb)
            .map(|(x, y)| (x[c] - y[c]).abs())
            .fold(0.0, f64::max);
        if scale > 0.0 {
            worst = worst.max(diff / scale);
        }
    }
    worst
}

fn first_difference(a: &[u8], b: &[u8]) -> String {
    let line = a
        .split(|&c| c == b'\n')
        .zip(b.split(|&c| c == b'\n'))
        .position(|(x, y)| x != y);
    match line {
        Some(l) => format!(" (first at line {})", l + 1),
        None => " (lengths differ)".into(),
    }
}

fn wait_with_timeout(
    mut child: std::process::Child,
    timeout: Duration,
) -> (Vec<u8>, Vec<u8>, bool) {
    use std::io::Read;
    let mut out = child.stdout.take().expect("stdout");
    let mut err = child.stderr.take().expect("stderr");
    let t_out = std::thread::spawn(move || {
        let mut v = Vec::new();
        out.read_to_end(&mut v).ok();
        v
    });
    let t_err = std::thread::spawn(move || {
        let mut v = Vec::new();
        err.read_to_end(&mut v).ok();
        v
    });
    let start = Instant::now();
    let ok = loop {
        match child.try_wait().expect("wait") {
            Some(s) => break s.success(),
            None if start.elapsed() > timeout => {
                eprintln!("child timed out after {timeout:?}; killing it");
                child.kill().ok();
                child.wait().ok();
                break false;
            }
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    (
        t_out.join().expect("stdout"),
        t_err.join().expect("stderr"),
        ok,
    )
}
