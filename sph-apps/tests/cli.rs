//! The `sphexa` binary itself: bad input is refused with a message naming
//! the value and what is allowed (never a panic); `sphexa cases` lists the
//! registry; a tiny run writes its outputs.

mod common;

use common::{assert_mentions, refused, s, scratch, sphexa, sphexa_command};
use std::path::{Path, PathBuf};

#[test]
fn unknown_case_is_named_with_the_registered_cases() {
    let e = refused(&["sedov-taylor", "--steps", "1", "-q"]);
    let mut words = vec!["sedov-taylor"];
    words.extend(sph_apps::cases::names());
    assert_mentions(&e, &words);
}

#[test]
fn zero_and_negative_sides_are_refused() {
    for side in ["0", "-3", "1001", "abc"] {
        let e = refused(&["sedov", "-n", side, "--steps", "1", "-q"]);
        assert_mentions(&e, &[&format!("'{side}'"), "--side", "4 to 1000"]);
    }
}

#[test]
fn zero_threads_are_refused() {
    for threads in ["0", "-2"] {
        let e = refused(&["sedov", "--threads", threads, "--steps", "1", "-q"]);
        assert_mentions(&e, &[&format!("'{threads}'"), "--threads", "at least 1"]);
    }
}

#[test]
fn negative_numbers_are_refused_with_the_allowed_range() {
    for (option, value, allowed) in [
        ("--alpha", "-1", ">= 0"),
        ("--conductivity", "-0.5", ">= 0"),
        ("--softening", "-1", ">= 0"),
        ("--theta", "-1", "positive"),
        ("--courant", "1.5", "(0, 1]"),
        ("--steps", "-1", "at least 1"),
        ("--alpha", "nan", "finite"),
    ] {
        let e = refused(&["evrard", "-n", "4", option, value, "-q"]);
        assert_mentions(&e, &[&format!("'{value}'"), option, allowed]);
    }
}

#[test]
fn negative_end_time_is_refused() {
    for t in ["-1", "0", "inf"] {
        let e = refused(&["sedov", "-n", "4", "--end-time", t, "-q"]);
        assert_mentions(&e, &[&format!("'{t}'"), "--end-time", "positive"]);
    }
}

#[test]
fn unknown_kernel_is_named_with_the_allowed_kernels() {
    let e = refused(&["sedov", "--kernel", "gauss", "--steps", "1", "-q"]);
    assert_mentions(&e, &["gauss", "--kernel", "m4", "wendland-c2", "sinc"]);
    let e = refused(&["sedov", "--kernel", "sinc:0", "--steps", "1", "-q"]);
    assert_mentions(&e, &["--kernel", "sinc:0", "1 <= n <= 1000"]);
}

#[test]
fn equations_of_state_are_named_with_the_accepted_forms() {
    for value in ["ideal:1", "gas:1", "isothermal:x", "polytropic:1"] {
        let e = refused(&["sedov", "--eos", value, "--steps", "1", "-q"]);
        assert_mentions(&e, &[value, "--eos", "ideal:GAMMA", "isothermal:C0"]);
    }
    // Each with what it cannot be used with, or on which case; refused
    // before anything is written.
    let out = scratch("eos-refused");
    let e = refused(&[
        "sedov",
        "--eos",
        "isothermal:1",
        "--conductivity",
        "1",
        "--steps",
        "1",
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_mentions(&e, &["isothermal:1", "conductivity"]);
    assert!(!out.join("config.toml").exists());
    let e = refused(&[
        "sedov",
        "--eos",
        "tait-ref:1",
        "--steps",
        "1",
        "-q",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_mentions(&e, &["tait-ref:1", "square-patch", "sedov"]);
}

#[test]
fn neighbour_counts_must_be_ordered() {
    let e = refused(&[
        "sedov", "--ng0", "200", "--ngmax", "150", "--steps", "1", "-q",
    ]);
    assert_mentions(&e, &["--ng0 200", "--ngmax 150", "at least 8"]);
}

#[test]
fn an_output_folder_that_cannot_be_created_is_refused() {
    let dir = scratch("bad-out");
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").expect("write a file");
    let bad = file.join("out");
    let bad = bad.to_str().expect("UTF-8 path");
    let e = refused(&["sedov", "-n", "4", "--steps", "1", "-q", "--out", bad]);
    assert_mentions(&e, &["--out", bad, "cannot create"]);
}

#[test]
fn cases_lists_every_registered_case() {
    let out = sphexa(&["cases"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for case in sph_apps::cases::registry() {
        let line = text
            .lines()
            .find(|l| l.split_whitespace().next() == Some(case.name()))
            .unwrap_or_else(|| panic!("{} not listed:\n{text}", case.name()));
        assert!(line.contains(case.description()), "{line}");
        assert!(line.contains(&case.default_side().to_string()), "{line}");
    }
}

#[test]
fn run_help_lists_the_cases_and_the_defaults() {
    let out = sphexa(&["run", "--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in sph_apps::cases::names() {
        assert!(
            text.contains(name),
            "{name} missing from run --help:\n{text}"
        );
    }
    for default in ["[default: sinc:6]", "[default: 100]", "[default: hilbert]"] {
        assert!(text.contains(default), "{default} missing:\n{text}");
    }
}

#[test]
fn a_tiny_sedov_run_writes_its_outputs() {
    let dir = scratch("sedov").join("out");
    let out = sphexa(&[
        "run",
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "8",
        "--steps",
        "2",
        "-q",
        "--out",
        dir.to_str().expect("UTF-8 path"),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "sphexa failed: {stderr}");
    let conserved = std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv");
    let mut lines = conserved.lines();
    assert!(lines.next().expect("header").starts_with("step,t,dt,"));
    // One row per step.
    assert_eq!(lines.count(), 2, "{conserved}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("sedov: 512 particles, 2 steps"), "{stdout}");
}

/// A side below the smallest glass block still runs: Evrard's sphere is
/// cut from a glass of at least `glass::MIN_SIDE` per side, tiled at the
/// asked spacing (35 particles at `-n 4`).
#[test]
fn evrard_below_the_smallest_glass_block_runs() {
    let dir = scratch("evrard-tiny");
    let out = sphexa_command()
        .args(["run", "evrard", "-n", "4", "--steps", "2", "-q", "--out"])
        .arg(dir.join("out"))
        .env("SPHEXA_GLASS_DIR", dir.join("glass"))
        .output()
        .expect("the sphexa binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "sphexa failed: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("evrard: 35 particles, 2 steps"), "{stdout}");
}

#[test]
fn unknown_scheme_is_named_with_the_presets() {
    let out = scratch("unknown-scheme");
    let out = out.to_str().unwrap();
    let e = refused(&[
        "sedov", "--scheme", "sph-ve", "--steps", "1", "-q", "--out", out,
    ]);
    let mut words = vec!["--scheme", "sph-ve"];
    words.extend(sph_core::PRESETS.iter().map(|p| p.0));
    assert_mentions(&e, &words);
}

#[test]
fn run_help_names_every_preset() {
    let out = sphexa(&["run", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for (name, _, _) in sph_core::PRESETS {
        assert!(help.contains(&format!("`{name}`")), "--help lacks {name}");
    }
}

/// `conserved.csv` of a tiny Sedov run with `extra` options.
fn tiny_sedov(name: &str, extra: &[&str]) -> String {
    let dir = scratch(name).join("out");
    // Global steps: these compare schemes and first steps step by step.
    let mut args = vec![
        "run",
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "8",
        "--steps",
        "3",
        "-q",
        "--out",
    ];
    args.push(dir.to_str().expect("UTF-8 path"));
    args.extend_from_slice(extra);
    let out = sphexa(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "sphexa {args:?} failed: {stderr}");
    std::fs::read_to_string(dir.join("conserved.csv")).expect("conserved.csv")
}

#[test]
fn a_scheme_preset_is_its_options() {
    let preset = tiny_sedov("preset-noh", &["--scheme", "noh"]);
    // `noh` is `paper` (Sedov's scheme until 2026-12-06) with these.
    let options = tiny_sedov(
        "options-noh",
        &[
            "--scheme",
            "paper",
            "--gradients",
            "kernel",
            "--av-switches",
            "on",
            "--alpha",
            "0.7",
        ],
    );
    let default = tiny_sedov("preset-default", &[]);
    assert_eq!(preset, options, "--scheme noh differs from its options");
    assert_ne!(preset, default, "--scheme noh changed nothing");
    // An option after the preset overrides it.
    let overridden = tiny_sedov(
        "preset-paper-alpha",
        &["--scheme", "noh", "--gradients", "iad"],
    );
    assert_ne!(overridden, preset);
}

#[test]
fn the_viscosity_form_is_an_option_and_recorded() {
    let ve = tiny_sedov("form-ve", &["--scheme", "ve"]);
    let same = tiny_sedov(
        "form-ve-sph-exa",
        &["--scheme", "ve", "--av-form", "sph-exa"],
    );
    let paper = tiny_sedov("form-ve-paper", &["--scheme", "ve", "--av-form", "paper"]);
    assert_eq!(ve, same, "--av-form sph-exa is ve's own form");
    assert_ne!(ve, paper, "--av-form paper changed nothing");
    // (tiny_sedov's folder, not emptied again by scratch())
    let config =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli-form-ve-paper/out/config.toml");
    let config = std::fs::read_to_string(config).expect("config.toml");
    assert!(config.contains("av-form = \"paper\""), "{config}");
    let e = refused(&["sedov", "--av-form", "beta"]);
    assert_mentions(&e, &["beta", "paper", "sph-exa"]);
}

/// A build without MPI refuses runs on more than one rank, in `bench
/// --ranks` and when an MPI launcher started it, instead of running the
/// whole problem once per rank into the same files.
#[cfg(not(feature = "mpi"))]
#[test]
fn a_build_without_mpi_refuses_more_than_one_rank() {
    let dir = scratch("no-mpi");
    let out = sphexa(
        &[
            "bench", "sedov", "--sizes", "8", "--ranks", "1,2", "-q", "--out",
        ]
        .iter()
        .copied()
        .chain([dir.to_str().expect("UTF-8")])
        .collect::<Vec<_>>(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "bench --ranks 1,2 succeeded: {stderr}"
    );
    assert_mentions(&stderr, &["--ranks 2", "without MPI", "--features mpi"]);
    assert!(
        !dir.join("runs").exists(),
        "bench started runs before refusing"
    );

    let out = sphexa_command()
        .args(["run", "sedov", "-n", "8", "--steps", "1", "-q", "--out"])
        .arg(dir.join("launched"))
        .env("OMPI_COMM_WORLD_SIZE", "2")
        .output()
        .expect("the sphexa binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a run as one of 2 ranks succeeded");
    assert_mentions(&stderr, &["one of 2 MPI ranks", "without MPI"]);
    assert!(!dir.join("launched").join("conserved.csv").exists());
}

#[test]
fn a_wind_shock_box_too_thin_for_the_kernel_is_refused_with_the_least_size() {
    let out = scratch("wind-shock-too-few");
    let out = out.to_str().unwrap();
    let e = refused(&["wind-shock", "-n", "16", "--steps", "1", "-q", "--out", out]);
    assert_mentions(&e, &["wind-shock", "16", "ng0 = 100", "-n 28"]);
}

/// A reader that stops early (`sphexa cases | head -1`) ends the listing
/// quietly: exit status 0, nothing on stderr, no panic.
#[test]
fn closed_stdout_ends_the_listing_quietly() {
    let mut child = sphexa_command()
        .arg("cases")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the sphexa binary runs");
    // Close the read end before the child writes: its first line meets a
    // broken pipe.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("sphexa finishes");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}: {err}", out.status);
    assert!(!err.contains("panicked"), "{err}");
}

/// The `dt` column of a `conserved.csv`.
fn dts(csv: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let k = header.iter().position(|&h| h == "dt").expect("dt column");
    lines
        .map(|l| l.split(',').nth(k).expect("dt").parse().expect("number"))
        .collect()
}

#[test]
fn first_step_criteria_skips_the_growth_from_dt0() {
    let ramp = dts(&tiny_sedov("first-step-default", &[]));
    let free = dts(&tiny_sedov(
        "first-step-criteria",
        &["--first-step", "criteria"],
    ));
    // SPH-EXA's start: 1.1 dt0 = 1.1e-6, then 1.1 per step.
    assert!((ramp[0] - 1.1e-6).abs() < 1e-18, "{ramp:?}");
    assert!((ramp[1] - 1.21e-6).abs() < 1e-18, "{ramp:?}");
    // The Courant step of the hot centre at 8^3 is ~1e-3: hundreds of dt0.
    assert!(free[0] > 100.0 * ramp[0], "{free:?}");
    // After it the growth limit holds again.
    assert!(free[1] <= 1.1 * free[0] * (1.0 + 1e-15), "{free:?}");
}

/// `sphexa spectrum` on a driven run's snapshot gives the spectrum and
/// ln rho PDF the run itself wrote at that time (`--spectra-every-time`)
/// to the byte, under block steps (the default: both hold the state at the
/// requested time) and global steps; there it also gives the width of ln
/// rho the run's curve recorded at that step (both exact sums; a block
/// run's curve row holds the state at the sub-step's end). A missing file
/// is named.
#[test]
fn spectrum_of_a_snapshot() {
    let dir = scratch("spectrum");
    for time_steps in ["block", "global"] {
        spectrum_matches_the_run(&dir, time_steps);
    }

    // A file that is not there is named.
    let missing = dir.join("missing.h5");
    let o = sphexa(&["spectrum", s(&missing)]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.h5"));
}

/// One turbulence run under `time_steps` with snapshots and spectra at
/// t = 0.05 and 0.1, each snapshot's spectrum against the run's.
fn spectrum_matches_the_run(dir: &Path, time_steps: &str) {
    let out = dir.join(format!("run-{time_steps}"));
    let o = sphexa(&[
        "run",
        "turbulence",
        "-n",
        "12",
        "--end-time",
        "0.1",
        "--time-steps",
        time_steps,
        "--snapshot-every-time",
        "0.05",
        "--spectra-every-time",
        "0.05",
        "--snapshot-fields",
        "x,y,z,vx,vy,vz,m,rho",
        "-q",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let curve = std::fs::read_to_string(out.join("curve.csv")).unwrap();
    let mut snaps: Vec<PathBuf> = std::fs::read_dir(out.join("snapshots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    snaps.sort();
    assert_eq!(snaps.len(), 2, "{snaps:?}");
    for snap in snaps {
        let name = snap.file_stem().unwrap().to_string_lossy().to_string();
        let step: u64 = name.trim_start_matches("snapshot_").parse().unwrap();
        let spec = dir.join(format!("spectrum-{time_steps}-{step}"));
        let o = sphexa(&["spectrum", s(&snap), "--out", s(&spec)]);
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mine = std::fs::read(spec.join("spectrum.csv")).unwrap();
        let run = std::fs::read(out.join(format!("spectra/spectrum_{step:08}.csv"))).unwrap();
        assert!(
            mine == run,
            "{time_steps}, step {step}: the run's spectrum differs from the snapshot's"
        );
        assert!(String::from_utf8_lossy(&mine).starts_with("k,E,E_sol,E_comp,cells"));
        let pdf = std::fs::read(spec.join("lnrho_pdf.csv")).unwrap();
        let run_pdf = std::fs::read(out.join(format!("spectra/lnrho_{step:08}.csv"))).unwrap();
        assert!(
            pdf == run_pdf,
            "{time_steps}, step {step}: the run's ln rho PDF differs from the snapshot's"
        );
        if time_steps == "block" {
            continue;
        }
        let width: f64 = text
            .split("width ")
            .nth(1)
            .and_then(|w| w.split_whitespace().next())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no width in: {text}"));
        // step, t, mach_rms, sigma_ln_rho, mean_ln_rho; the line prints 5 digits.
        let row: Vec<f64> = curve
            .lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap())
                    .collect::<Vec<f64>>()
            })
            .find(|r| r[0] == step as f64)
            .unwrap();
        assert!(
            (width / row[3] - 1.0).abs() < 1e-4,
            "width {width} against {}",
            row[3]
        );
    }
}

/// Block time steps: `timings.csv` has a row per synchronisation step
/// whose sub-steps and updates add up to the run's (summary.json, whose
/// `time_bins` hold every particle at the end), and
/// `conserved.csv` a row at each synchronisation point, the first
/// sub-step of each timings row, at most the longest step apart.
#[test]
fn a_block_step_run_writes_a_row_per_synchronisation_step() {
    let dir = scratch("sedov-block-rows");
    common::ok(&[
        "sedov",
        "-n",
        "12",
        "-q",
        "--time-steps",
        "block",
        "--end-time",
        "0.05",
        "--out",
        s(&dir),
    ]);
    let table = |file: &str| -> (Vec<String>, Vec<Vec<String>>) {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap()
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(str::to_owned).collect())
            .collect();
        (header, rows)
    };
    let (th, mut trows) = table("timings.csv");
    let mean = trows.pop().unwrap();
    assert_eq!(mean[0], "mean_2..N");
    let col = |h: &[String], name: &str| h.iter().position(|c| c == name).unwrap();
    let (cs, cu) = (col(&th, "substeps"), col(&th, "updates"));
    let sum = |k: usize| {
        trows
            .iter()
            .map(|r| r[k].parse::<u64>().unwrap())
            .sum::<u64>()
    };
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(sum(cs), summary["steps"].as_u64().unwrap());
    assert_eq!(sum(cu), summary["particle_updates"].as_u64().unwrap());
    assert_eq!(summary["time_steps"], "block");
    // The bins at the end hold every particle, longest steps first.
    let bins = summary["time_bins"].as_array().unwrap();
    let held: u64 = bins.iter().map(|b| b["particles"].as_u64().unwrap()).sum();
    assert_eq!(held, summary["particles"].as_u64().unwrap());
    let dts: Vec<f64> = bins.iter().map(|b| b["dt"].as_f64().unwrap()).collect();
    assert!(
        dts.windows(2).all(|w| w[0] > w[1]) && dts[0] <= 0.05 / 4.0,
        "{dts:?}"
    );
    assert!(
        trows.iter().any(|r| r[cs] != "1"),
        "some row of several sub-steps"
    );
    let (ch, crows) = table("conserved.csv");
    let steps = |rows: &[Vec<String>]| rows.iter().map(|r| r[0].clone()).collect::<Vec<_>>();
    assert_eq!(steps(&crows), steps(&trows));
    // The points advance by at most the longest step (a quarter of the
    // run by default) and the run ends at its end time.
    let ct = col(&ch, "t");
    let times: Vec<f64> = crows.iter().map(|r| r[ct].parse().unwrap()).collect();
    assert_eq!(times[0], 0.0);
    for w in times.windows(2) {
        assert!(
            w[1] > w[0] && w[1] - w[0] <= 0.05 / 4.0 * (1.0 + 1e-12),
            "{w:?}"
        );
    }
    assert_eq!(summary["t_end"].as_f64(), Some(0.05));
}

/// Block time steps with smoothing lengths held fixed (the square
/// patch): a snapshot between sub-steps keeps every h as it is (the drift
/// does not change it there), while the density is predicted to the time.
#[test]
fn a_fixed_h_block_step_snapshot_keeps_h() {
    use sph_io::{FieldData, H5Part, Selection, SnapshotReader};
    let dir = scratch("square-patch-block-snapshot-at");
    common::ok(&[
        "square-patch",
        "-n",
        "8",
        "-q",
        "--time-steps",
        "block",
        "--end-time",
        "0.01",
        "--snapshot-at",
        "0.00123",
        "--snapshot-fields",
        "id,h,rho",
        "--write-particles",
        "--out",
        s(&dir),
    ]);
    let snap: Vec<PathBuf> = std::fs::read_dir(dir.join("snapshots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(snap.len(), 1, "{snap:?}");
    let mid = H5Part.read_step(&snap[0], 0, &Selection::All).unwrap();
    assert_eq!(mid.time, 0.00123);
    let Some(FieldData::F64(h)) = mid.field("h") else {
        panic!("no h")
    };
    // The final state's h, by id (fixed: the same as at every time).
    let text = std::fs::read_to_string(dir.join("particles.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (ci, ch) = (
        header.iter().position(|&c| c == "id").unwrap(),
        header.iter().position(|&c| c == "h").unwrap(),
    );
    let mut h_end = std::collections::HashMap::new();
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        h_end.insert(f[ci].parse::<u64>().unwrap(), f[ch].parse::<f64>().unwrap());
    }
    let Some(FieldData::U64(ids)) = mid.field("id") else {
        panic!("no id")
    };
    for (id, hv) in ids.iter().zip(h) {
        assert_eq!(*hv, h_end[id], "particle {id}");
    }
}

/// Block time steps: a snapshot asked for at t = 0.0123, inside a
/// sub-step, holds that time exactly, and positions where the drift puts
/// them then: on the line between the states at the sub-step's ends
/// (snapshots of every sub-step of the same run, which is the same with
/// or without them).
#[test]
fn a_block_step_snapshot_lands_at_the_requested_time() {
    use sph_io::{FieldData, H5Part, Selection, SnapshotReader};
    let dir = scratch("sedov-block-snapshot-at");
    let t_out = 0.0123;
    let run = |name: &str, extra: &[&str]| {
        let mut args = vec![
            "sedov",
            "-n",
            "12",
            "-q",
            "--time-steps",
            "block",
            "--end-time",
            "0.05",
            // No synchronisation point (and its re-sort) between the
            // sub-steps around t_out.
            "--dt-max",
            "0.00625",
            "--snapshot-fields",
            "id,x,y,z",
            "--out",
        ];
        let out = dir.join(name);
        args.push(s(&out));
        args.extend_from_slice(extra);
        common::ok(&args);
        out
    };
    let every = run("every", &["--snapshot-every-steps", "1"]);
    let at = run("at", &["--snapshot-at", "0.0123"]);
    let conserved = |d: &PathBuf| std::fs::read(d.join("conserved.csv")).unwrap();
    assert!(
        conserved(&every) == conserved(&at),
        "snapshots changed the run"
    );
    let snaps = |d: &PathBuf| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d.join("snapshots"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        v.sort();
        v
    };
    let read = |p: &PathBuf| H5Part.read_step(p, 0, &Selection::All).unwrap();
    let got = snaps(&at);
    assert_eq!(got.len(), 1, "{got:?}");
    let mid = read(&got[0]);
    assert_eq!(mid.time, t_out);
    // The sub-step holding t_out, from the every-step snapshots.
    let all: Vec<_> = snaps(&every).iter().map(read).collect();
    let k = all.iter().position(|s| s.time >= t_out).unwrap();
    let (a, b) = (&all[k - 1], &all[k]);
    assert!(
        a.time < t_out && mid.step == b.step,
        "{} {} {}",
        a.time,
        b.time,
        mid.step
    );
    let w = (t_out - a.time) / (b.time - a.time);
    let f64s = |s: &sph_io::Snapshot, n: &str| match s.field(n) {
        Some(FieldData::F64(v)) => v.clone(),
        _ => panic!("no {n}"),
    };
    assert!(a.field("id") == mid.field("id") && b.field("id") == mid.field("id"));
    let mut worst: f64 = 0.0;
    for c in ["x", "y", "z"] {
        let (xa, xb, xm) = (f64s(a, c), f64s(b, c), f64s(&mid, c));
        for i in 0..xm.len() {
            if (xb[i] - xa[i]).abs() > 0.5 {
                continue; // wrapped across the periodic box in the sub-step
            }
            worst = worst.max((xm[i] - (xa[i] + w * (xb[i] - xa[i]))).abs());
        }
    }
    assert!(
        worst < 1e-14,
        "largest departure from the drift line {worst:e}"
    );
}

/// Block time steps are each case's default, named in `config.toml`,
/// with driving turned on too and for driven turbulence; a run that asks
/// for global steps steps globally; under block steps `--steps N` stops
/// at the case's end time at the latest.
#[test]
fn cases_run_block_time_steps() {
    let run_case = |case: &str, name: &str, extra: &[&str]| -> (String, serde_json::Value) {
        let dir = scratch(name);
        let mut args = vec![case, "-n", "8", "-q", "--out", s(&dir)];
        args.extend_from_slice(extra);
        common::ok(&args);
        let config = std::fs::read_to_string(dir.join("config.toml")).unwrap();
        let line = config
            .lines()
            .find(|l| l.starts_with("time-steps"))
            .unwrap_or_else(|| panic!("no time-steps in {config}"))
            .to_owned();
        let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        (line, serde_json::from_str(&summary).unwrap())
    };
    let run = |name: &str, extra: &[&str]| run_case("sedov", name, extra);
    let (block, _) = run("default-block", &["--steps", "2"]);
    assert_eq!(block, r#"time-steps = "block""#);
    let (stirred, _) = run("default-stirred", &["--steps", "2", "--stir", "on"]);
    assert_eq!(stirred, r#"time-steps = "block""#);
    let turbulence = |name: &str, extra: &[&str]| run_case("turbulence", name, extra);
    let (driven, s) = turbulence("turbulence-default", &["--steps", "4"]);
    assert_eq!(driven, r#"time-steps = "block""#);
    assert_eq!(s["steps"].as_u64(), Some(4), "{s}");
    let (driven, _) = turbulence(
        "turbulence-global",
        &["--steps", "2", "--time-steps", "global"],
    );
    assert_eq!(driven, r#"time-steps = "global""#);
    let (asked, _) = run("asked-global", &["--steps", "2", "--time-steps", "global"]);
    assert_eq!(asked, r#"time-steps = "global""#);
    // The case's end time, 0.05, comes first.
    let (_, summary) = run("steps-past-end", &["--steps", "100000"]);
    assert_eq!(summary["t_end"].as_f64(), Some(0.05), "{summary}");
    assert!(summary["steps"].as_u64().unwrap() < 100000, "{summary}");
}
