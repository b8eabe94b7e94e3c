//! Snapshots, checkpoints and configuration files through the `sphexa`
//! binary: a restarted run continues to the bit, a run killed with SIGKILL
//! while writing restarts from its last complete checkpoint, a run repeats
//! from the `config.toml` it wrote, and SPH-EXA-layout files start a case.

mod common;

use common::{initial_fields, ok, refused, s, scratch, sphexa_command, write_sphexa_file};
use sph_io::{FieldData, H5Part, Selection, Snapshot, SnapshotReader};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn read(path: &Path) -> Snapshot {
    H5Part
        .read_step(path, 0, &Selection::All)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The same particles in the same state: every field, step, time, dt and
/// box to the bit (the `config` attribute records how each run was started
/// and may differ).
fn assert_same_state(a: &Snapshot, b: &Snapshot, what: &str) {
    let mut a = a.clone();
    let mut b = b.clone();
    for x in [&mut a, &mut b] {
        x.attrs.retain(|(n, _)| n != "config");
    }
    assert!(!a.fields.is_empty(), "{what}: no fields");
    assert!(a.bits_eq(&b), "{what}: states differ");
}

/// Sedov 20^3: 40 steps in one run against 20 steps, then a restart from
/// the checkpoint of step 20 for 20 more, in the same output folder.
#[test]
fn a_restarted_run_continues_bit_identically() {
    let dir = scratch("sedov");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let common = [
        "-n",
        "20",
        "-q",
        "--checkpoint-every",
        "20",
        "--snapshot-every-steps",
        "20",
        "--snapshot-fields",
        "id,x,y,z,vx,vy,vz,h,u,rho,p,du_prev",
    ];
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["sedov", "--time-steps", "global", "--out", s(out)];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        ok(&args);
    };
    run(&a, &["--steps", "40"]);
    run(&b, &["--steps", "20"]);
    let ckpt = b.join("checkpoints/checkpoint_00000020.h5");
    // The restart takes case and options from the checkpoint.
    ok(&["--restart", s(&ckpt), "--steps", "40", "-q"]);

    let conserved = |d: &Path| std::fs::read_to_string(d.join("conserved.csv")).unwrap();
    let (ca, cb) = (conserved(&a), conserved(&b));
    assert_eq!(ca.lines().count(), 41, "header + 40 steps");
    assert!(ca == cb, "conserved.csv differs:\n{ca}\n---\n{cb}");
    for file in [
        "snapshots/snapshot_00000040.h5",
        "checkpoints/checkpoint_00000040.h5",
    ] {
        assert_same_state(&read(&a.join(file)), &read(&b.join(file)), file);
    }
    // The final snapshot holds what was asked, of every particle.
    let snap = read(&a.join("snapshots/snapshot_00000040.h5"));
    assert_eq!((snap.step, snap.len()), (40, 8000));
    let mut ids = snap
        .field("id")
        .and_then(FieldData::as_u64)
        .unwrap()
        .to_vec();
    ids.sort_unstable();
    assert_eq!(ids, (0..8000).collect::<Vec<u64>>());
    // A checkpoint restarts only a run of its own case.
    let e = refused(&[
        "noh",
        "--restart",
        s(&ckpt),
        "--steps",
        "21",
        "-q",
        "--out",
        s(&dir.join("c")),
    ]);
    assert!(e.contains("sedov") && e.contains("noh"), "{e}");
}

/// `sphexa run CASE -n SIDE` under block time steps, checkpoints due
/// every 10 sub-steps (all kept) and the final particles written, into
/// `out`, with `extra` options.
fn block_run(case: &str, side: &str, out: &Path, extra: &[&str]) {
    let mut args = vec![
        case,
        "-n",
        side,
        "-q",
        "--time-steps",
        "block",
        "--checkpoint-every",
        "10",
        "--checkpoint-keep",
        "0",
        "--write-particles",
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    ok(&args);
}

/// The checkpoint files of the run in `dir`, sorted.
fn checkpoints(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir.join("checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Each of `files` is the same, byte for byte, in `a` and `b`.
fn same_files(a: &Path, b: &Path, files: &[&str]) {
    for file in files {
        let (fa, fb) = (
            std::fs::read(a.join(file)).unwrap(),
            std::fs::read(b.join(file)).unwrap(),
        );
        assert!(fa == fb, "{file} differs after the restart");
    }
}

/// Block time steps: checkpoints fall due every 10 sub-steps and are
/// written at the next synchronisation point (every particle's step
/// ended). Sedov 16^3 to t = 0.05 in one run against 55 sub-steps, then a
/// restart from the checkpoint of sub-step 51 to the end, in the same
/// folder: the same conserved.csv and final state to the bit. A block
/// checkpoint continues under block steps only, to its end or another.
#[test]
fn a_restarted_block_step_run_continues_bit_identically() {
    let dir = scratch("sedov-block");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let run = |out: &Path, extra: &[&str]| block_run("sedov", "16", out, extra);
    run(&a, &["--end-time", "0.05"]);
    run(&b, &["--steps", "55"]);
    // Due at 10, 20, ...; written where every particle's step ends.
    let written = checkpoints(&a);
    assert!(
        written.len() >= 2 && !written.contains(&"checkpoint_00000010.h5".to_string()),
        "{written:?}"
    );
    // The last checkpoint of the run stopped after 55 sub-steps.
    let last = checkpoints(&b)
        .pop()
        .expect("a checkpoint of the 55 sub-steps");
    let ckpt = b.join("checkpoints").join(last);
    let e = refused(&["--restart", s(&ckpt), "--time-steps", "global", "-q"]);
    assert!(e.contains("block-step"), "{e}");
    ok(&["--restart", s(&ckpt), "--end-time", "0.05", "-q"]);
    same_files(&a, &b, &["conserved.csv", "particles.csv"]);
    // The end's checkpoint (the same sub-step in both).
    let end = checkpoints(&a)
        .pop()
        .expect("checkpoints of the straight run");
    assert_eq!(checkpoints(&b).last(), Some(&end));
    assert_same_state(
        &read(&a.join("checkpoints").join(&end)),
        &read(&b.join("checkpoints").join(&end)),
        "the last checkpoint",
    );
    // Another end: the run starts a new time line at its first sub-step
    // (a synchronisation point) and lands on that end.
    let c = dir.join("c");
    ok(&[
        "--restart",
        s(&ckpt),
        "--end-time",
        "0.06",
        "--out",
        s(&c),
        "-q",
    ]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(c.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["t_end"].as_f64(), Some(0.06), "{summary}");
}

/// Driven turbulence under block time steps: a restart from a
/// synchronisation-point checkpoint continues the driving (OU phases,
/// generator, work) and each particle's kept stirring acceleration to the
/// bit. 8^3 for 60 sub-steps in one run against 30, then a restart from
/// the last checkpoint of those to sub-step 60 (a time line to the case's
/// end, t = 10, in each). The box's particles all take about the same
/// step, so its lines are one step for all and that checkpoint lies at a
/// line's end, which a restart refused before 2026-12-05.
#[test]
fn a_restarted_stirred_block_step_run_continues_bit_identically() {
    let dir = scratch("turbulence-block");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let run = |out: &Path, extra: &[&str]| block_run("turbulence", "8", out, extra);
    run(&a, &["--steps", "60"]);
    run(&b, &["--steps", "30"]);
    let mut written = checkpoints(&b);
    let ckpt = b
        .join("checkpoints")
        .join(written.pop().expect("a checkpoint"));
    ok(&["--restart", s(&ckpt), "--steps", "60", "-q"]);
    same_files(&a, &b, &["conserved.csv", "particles.csv"]);
    // The driving did work in both.
    let conserved = std::fs::read_to_string(a.join("conserved.csv")).unwrap();
    let last = conserved.lines().last().unwrap();
    let w: f64 = last.rsplit(',').next().unwrap().parse().unwrap();
    assert!(w > 0.0, "W_ext {w} in {last}");
}

/// Kill test: a run checkpointing every step is killed with SIGKILL inside
/// its 4th checkpoint write, with the data in `checkpoint_00000004.h5.tmp`
/// and before the rename (the test hook of `sph_apps::checkpoint` pauses
/// it there and says so with a marker file); the newest complete
/// checkpoint (step 3) reads back and restarts, and the restarted run
/// gives the conserved.csv of a run that was never interrupted.
#[test]
fn a_killed_run_restarts_from_its_last_complete_checkpoint() {
    use sph_apps::checkpoint::{PAUSE_MARKER, PAUSE_VAR};
    const PAUSE_IN: u64 = 4;
    let dir = scratch("kill");
    let (k, u) = (dir.join("killed"), dir.join("uninterrupted"));
    let args = |out: &Path, steps: &str| -> Vec<String> {
        [
            "run",
            "sedov",
            "--time-steps",
            "global",
            "-n",
            "16",
            "-q",
            "--checkpoint-every",
            "1",
            "--checkpoint-keep",
            "3",
            "--steps",
            steps,
            "--out",
            s(out),
        ]
        .map(str::to_owned)
        .to_vec()
    };
    let marks = dir.join("marks");
    std::fs::create_dir_all(&marks).unwrap();
    // 10 steps: should the hook not pause, the run ends by itself and the
    // test fails instead of waiting.
    let mut child = sphexa_command()
        .args(args(&k, "10"))
        .env(PAUSE_VAR, format!("{PAUSE_IN}:{}", s(&marks)))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("sphexa starts");
    let ckdir = k.join("checkpoints");
    let listing = |ext: &str| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(&ckdir)
            .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
            .unwrap_or_default();
        v.retain(|p| p.to_string_lossy().ends_with(ext));
        v.sort();
        v
    };
    let start = Instant::now();
    while !marks.join(PAUSE_MARKER).exists() {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            panic!(
                "the run ended ({status}) without pausing in checkpoint {PAUSE_IN}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        if start.elapsed() > Duration::from_secs(120) {
            child.kill().ok();
            panic!("no pause in checkpoint {PAUSE_IN} in two minutes");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    // The pause blocks the writer for good: what is on disk now is what
    // the kill leaves.
    let tmp_at_kill = listing(".h5.tmp");
    child.kill().expect("SIGKILL"); // std's kill is SIGKILL on Unix
    child.wait().unwrap();
    let step = PAUSE_IN - 1;
    let name = |step: u64| format!("checkpoint_{step:08}.h5");
    assert_eq!(
        tmp_at_kill,
        [ckdir.join(format!("{}.tmp", name(PAUSE_IN)))],
        "the kill did not land during the write of checkpoint {PAUSE_IN}"
    );
    assert_eq!(listing(".h5.tmp"), tmp_at_kill, "the .tmp went away");
    let complete = listing(".h5");
    assert_eq!(
        complete,
        (1..=step).map(|k| ckdir.join(name(k))).collect::<Vec<_>>()
    );
    let last = complete.last().expect("a complete checkpoint").clone();
    // It reads back whole (checksums verified).
    let ck = read(&last);
    assert_eq!((ck.step, ck.len()), (step, 16 * 16 * 16));
    // It restarts, into the same folder, for 3 more steps.
    let target = (step + 3).to_string();
    ok(&["--restart", s(&last), "--steps", &target, "-q"]);
    let mut uargs = args(&u, &target);
    uargs.remove(0);
    let uargs: Vec<&str> = uargs.iter().map(String::as_str).collect();
    ok(&uargs);
    let conserved = |d: &Path| std::fs::read_to_string(d.join("conserved.csv")).unwrap();
    assert_eq!(conserved(&k).lines().count() as u64, step + 4);
    assert!(conserved(&k) == conserved(&u), "the restarted run differs");
}

#[test]
fn a_run_repeats_from_its_config_and_the_command_line_overrides_the_file() {
    let dir = scratch("config");
    let file = dir.join("run.toml");
    std::fs::write(
        &file,
        format!(
            "case = \"sedov\"\nside = 8\nsteps = 5\ntime-steps = \"global\"\nalpha = 0.7\nav-switches = \"on\"\nquiet = true\nsnapshot-at = [0.0]\nout = \"{}\"\n",
            s(&dir.join("never"))
        ),
    )
    .unwrap();
    let first = dir.join("first");
    ok(&["--config", s(&file), "--steps", "3", "--out", s(&first)]);
    let conserved = |d: &Path| std::fs::read_to_string(d.join("conserved.csv")).unwrap();
    assert_eq!(
        conserved(&first).lines().count(),
        4,
        "--steps 3 overrides steps = 5"
    );
    assert!(!dir.join("never").exists(), "--out overrides out");
    let resolved = std::fs::read_to_string(first.join("config.toml")).unwrap();
    for line in [
        "steps = 3",
        "alpha = 0.7",
        "av-switches = \"on\"",
        "side = 8",
        "case = \"sedov\"",
    ] {
        assert!(
            resolved.lines().any(|l| l == line),
            "{line} not in\n{resolved}"
        );
    }
    // A snapshot at t = 0 comes after step 1, with the run's settings.
    let snap = read(&first.join("snapshots/snapshot_00000001.h5"));
    assert!(matches!(snap.attr("config"), Some(sph_io::Attr::Str(c)) if *c == resolved));
    // The resolved configuration repeats the run (into another folder).
    let again = dir.join("again");
    ok(&[
        "--config",
        s(&first.join("config.toml")),
        "--out",
        s(&again),
    ]);
    assert_eq!(conserved(&first), conserved(&again));
    // And it differs from the defaults (the file's alpha and switches apply).
    let plain = dir.join("plain");
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "8",
        "--steps",
        "3",
        "-q",
        "--out",
        s(&plain),
    ]);
    assert_ne!(conserved(&first), conserved(&plain));
}

#[test]
fn bad_configuration_files_are_named_with_what_is_allowed() {
    let dir = scratch("bad-config");
    let file = dir.join("bad.toml");
    let check = |text: &str, words: &[&str]| {
        std::fs::write(&file, text).unwrap();
        let e = refused(&["--config", s(&file)]);
        for w in words {
            assert!(e.contains(w), "{w:?} missing from: {e}");
        }
    };
    check(
        "case = \"sedov\"\nsides = 8\n",
        &[
            "bad.toml",
            "'sides'",
            "allowed keys",
            "side",
            "end-time",
            "snapshot-fields",
        ],
    );
    check(
        "case = \"sedov\"\nside = 0\n",
        &["bad.toml", "'side'", "4 to 1000"],
    );
    check("case = \"sedov\"\nalpha = \"lots\"\n", &["'alpha'", ">= 0"]);
    check(
        "case = \"sedov\"\nquiet = 1\n",
        &["'quiet'", "true or false"],
    );
    check("side = [", &["bad.toml", "TOML"]);
    check("side = 8\n", &["no case"]);
    let e = refused(&[
        "sedov",
        "--snapshot-fields",
        "x,density",
        "--snapshot-every-steps",
        "1",
    ]);
    assert!(e.contains("'density'") && e.contains("rho"), "{e}");
    // The paper's scheme has no per-particle alpha.
    let e = refused(&[
        "sedov",
        "--scheme",
        "paper",
        "-n",
        "8",
        "--steps",
        "1",
        "-q",
        "--snapshot-fields",
        "alpha",
        "--snapshot-every-steps",
        "1",
        "--out",
        s(&dir.join("o")),
    ]);
    assert!(e.contains("'alpha'"), "{e}");
    let e = refused(&["sedov", "--checkpoint-every", "auto"]);
    assert!(e.contains("--mtbf"), "{e}");
    let e = refused(&["sedov", "--checkpoint-every", "often"]);
    assert!(
        e.contains("'often'") && e.contains("time:T") && e.contains("auto"),
        "{e}"
    );
    let e = refused(&["sedov", "--checkpoint-every", "auto", "--mtbf", "soon"]);
    assert!(e.contains("'soon'") && e.contains("6h"), "{e}");
    let e = refused(&["--restart", s(&dir.join("missing.h5"))]);
    assert!(e.contains("missing.h5"), "{e}");
}

/// Young/Daly: the interval is sqrt(2 C M) with C the measured write time.
#[test]
fn auto_checkpoints_report_the_young_daly_interval() {
    let dir = scratch("auto");
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "8",
        "--steps",
        "4",
        "-q",
        "--checkpoint-every",
        "auto",
        "--mtbf",
        "1h",
        "--out",
        s(&dir),
    ]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let io = &summary["io"];
    let c = io["checkpoint_seconds_mean"].as_f64().unwrap();
    let interval = io["checkpoint_interval_s"].as_f64().unwrap();
    // One checkpoint (after step 1, to measure C); the next is sqrt(2 C M)
    // away, far beyond this 4-step run.
    assert_eq!(io["checkpoints"].as_u64(), Some(1));
    assert!(
        ((interval * interval) / (2.0 * c * 3600.0) - 1.0).abs() < 1e-9,
        "{io}"
    );
}

/// An SPH-EXA-layout file (group Step#0, 1-D datasets named as SPH-EXA
/// names them, no checksums, no `id`, attributes `time`, `iteration`,
/// `minDt`, `box`) holding the Sedov initial state starts the case: the run
/// is the one the case makes itself.
#[test]
fn an_sphexa_layout_file_is_read_as_initial_conditions() {
    use hdf5_pure::AttrValue;
    let dir = scratch("init");
    let side = 10;
    let scene = sph_apps::cases::lookup("sedov")
        .unwrap()
        .setup(side, sph_core::HydroConfig::default())
        .unwrap();
    let p = &scene.particles;
    let attrs = [
        ("time", AttrValue::F64(0.0)),
        ("iteration", AttrValue::I64(0)),
        ("minDt", AttrValue::F64(1e-6)),
        (
            "box",
            AttrValue::F64Array(vec![-0.5, 0.5, -0.5, 0.5, -0.5, 0.5]),
        ),
    ];
    let fields = initial_fields(p);
    let file = dir.join("sedov_ic.h5");
    write_sphexa_file(&file, &attrs, &fields);
    let (from_file, own) = (dir.join("from-file"), dir.join("own"));
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "--init",
        s(&file),
        "--steps",
        "3",
        "-q",
        "--out",
        s(&from_file),
    ]);
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "10",
        "--steps",
        "3",
        "-q",
        "--out",
        s(&own),
    ]);
    let conserved = |d: &Path| std::fs::read_to_string(d.join("conserved.csv")).unwrap();
    assert_eq!(conserved(&from_file).lines().count(), 4);
    assert_eq!(conserved(&from_file), conserved(&own));
    // A file without u is refused, naming the field.
    let bad = dir.join("no_u.h5");
    let no_u: Vec<(&str, &[f64])> = ["x", "y", "z", "h", "m"].map(|n| (n, &p.x[..])).to_vec();
    write_sphexa_file(&bad, &[], &no_u);
    let e = refused(&[
        "sedov",
        "--init",
        s(&bad),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&own),
    ]);
    assert!(e.contains("'u'") && e.contains("no_u.h5"), "{e}");
}

/// A SWIFT-layout file (box `[0, 1)`, SWIFT's cubic-spline `h`) holding
/// the Sedov initial state starts the case: placed on the case's centred
/// box, `h` converted back, the run is the case's own to rounding (the
/// shift by 1/2 and the `h` factor round); a step spec on it, and a file in
/// neither layout, are refused by name.
#[test]
fn a_swift_layout_file_is_read_as_initial_conditions() {
    use sph_io::swift::{write_swift, SwiftKernel, SwiftParticles};
    let dir = scratch("init-swift");
    let scene = sph_apps::cases::lookup("sedov")
        .unwrap()
        .setup(10, sph_core::HydroConfig::default())
        .unwrap();
    let p = &scene.particles;
    let mut gas = SwiftParticles {
        x: p.x.clone(),
        y: p.y.clone(),
        z: p.z.clone(),
        vx: p.vx.clone(),
        vy: p.vy.clone(),
        vz: p.vz.clone(),
        m: p.m.clone(),
        h: p.h.clone(),
        u: p.u.clone(),
        id: p.id.clone(),
        box_size: [1.0; 3],
        ..SwiftParticles::default()
    };
    gas.uncentre();
    gas.scale_h(1.0 / SwiftKernel::CubicSpline.to_sph_exa_h());
    let file = dir.join("sedov_ic.hdf5");
    write_swift(&file, &gas).unwrap();
    let (from_file, own) = (dir.join("from-file"), dir.join("own"));
    let run = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "sedov",
            "--time-steps",
            "global",
            "--steps",
            "3",
            "-q",
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        ok(&args);
    };
    run(&["--init", s(&file)], &from_file);
    run(&["-n", "10"], &own);
    let rows = |d: &Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(d.join("conserved.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect()
    };
    let (a, b) = (rows(&from_file), rows(&own));
    assert_eq!(a.len(), 3);
    // Columns t, dt, E_kin, E_int: every step's time, step and energies
    // agree to rounding.
    for (ra, rb) in a.iter().zip(&b) {
        for k in [1, 2, 3, 4] {
            let scale = rb[k].abs().max(1e-300);
            assert!(
                (ra[k] - rb[k]).abs() <= 1e-9 * scale,
                "column {k}: {} vs {}",
                ra[k],
                rb[k]
            );
        }
    }
    let e = refused(&[
        "sedov",
        "--init",
        &format!("{}:1", s(&file)),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&own),
    ]);
    assert!(e.contains("one step") && e.contains("sedov_ic.hdf5"), "{e}");
    let junk = dir.join("junk.hdf5");
    std::fs::write(&junk, b"not an HDF5 file at all").unwrap();
    let e = refused(&[
        "sedov",
        "--init",
        s(&junk),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&own),
    ]);
    assert!(e.contains("neither") && e.contains("junk.hdf5"), "{e}");
}

/// `--snapshot-format swift` writes the state our own snapshot holds at
/// the same step of the same run: positions moved to `[0, L)`, SWIFT's `h`
/// (ours times `swift_h_per_h` of the kernel), the rest as they are; the
/// file starts a run again with `--init`.
#[test]
fn a_swift_snapshot_holds_the_state_of_ours() {
    use sph_io::swift::{read_swift, swift_h_per_h};
    let dir = scratch("snap-swift");
    let (ours, theirs) = (dir.join("ours"), dir.join("swift"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "sedov",
            "--time-steps",
            "global",
            "-n",
            "10",
            "--steps",
            "4",
            "-q",
            "--snapshot-every-steps",
            "4",
            "--out",
            s(out),
        ];
        args.extend_from_slice(extra);
        ok(&args);
    };
    run(
        &ours,
        &["--snapshot-fields", "x,y,z,vx,vy,vz,h,m,u,rho,p,id"],
    );
    run(&theirs, &["--snapshot-format", "swift"]);
    let a = read(&ours.join("snapshots/snapshot_00000004.h5"));
    let b = read_swift(&theirs.join("snapshots/snapshot_00000004.hdf5")).unwrap();
    let g = &b.particles;
    assert_eq!(g.len(), 1000);
    assert_eq!(g.box_size, [1.0; 3]);
    assert_eq!(g.time, a.time);
    let f = |n: &str| a.field(n).and_then(FieldData::as_f64).unwrap().to_vec();
    let ids = match a.field("id") {
        Some(FieldData::U64(v)) => v.clone(),
        _ => panic!("ids"),
    };
    // Our rows by id, to compare row for row.
    let row: std::collections::HashMap<u64, usize> =
        ids.iter().enumerate().map(|(i, &id)| (id, i)).collect();
    let kernel = sph_kernels::KernelChoice::Sinc(6.0).exact().unwrap();
    let factor = swift_h_per_h(|v| kernel.shape(v));
    let (x, y, z, h) = (f("x"), f("y"), f("z"), f("h"));
    let (u, rho, p, vx) = (f("u"), f("rho"), f("p"), f("vx"));
    for (k, id) in g.id.iter().enumerate() {
        let i = row[id];
        for (got, want) in [(g.x[k], x[i]), (g.y[k], y[i]), (g.z[k], z[i])] {
            assert!(
                (got - (want + 0.5)).abs() <= 1e-15,
                "id {id}: {got} vs {want}"
            );
            assert!((0.0..1.0).contains(&got));
        }
        assert_eq!(g.h[k], h[i] * factor, "id {id}");
        assert_eq!((g.u[k], g.vx[k]), (u[i], vx[i]), "id {id}");
        assert_eq!(g.rho.as_ref().unwrap()[k], rho[i], "id {id}");
        assert_eq!(g.p.as_ref().unwrap()[k], p[i], "id {id}");
    }
    let again = dir.join("again");
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "--init",
        s(&theirs.join("snapshots/snapshot_00000004.hdf5")),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&again),
    ]);
    let e = refused(&[
        "sedov",
        "--steps",
        "1",
        "--snapshot-every-steps",
        "1",
        "--snapshot-format",
        "swift",
        "--snapshot-fields",
        "x",
        "-q",
        "--out",
        s(&again),
    ]);
    assert!(
        e.contains("--snapshot-fields") && e.contains("swift"),
        "{e}"
    );
}

/// Every registered case (AV switches, self-gravity with an open box that
/// grows, a referenced equation of state, conductivity) restarts to the
/// bit: 6 steps against 3 + restart + 3.
#[test]
fn every_case_restarts_bit_identically() {
    for case in sph_apps::cases::names() {
        let dir = scratch(&format!("case-{case}"));
        let (a, b) = (dir.join("a"), dir.join("b"));
        // wind-shock's box is 0.25 across: at 8 per unit length the
        // kernel's support would exceed half of it.
        let side = if case == "wind-shock" { "32" } else { "8" };
        let run = |out: &Path, steps: &str| {
            ok(&[
                case,
                "--time-steps",
                "global",
                "-n",
                side,
                "-q",
                "--checkpoint-every",
                "3",
                "--steps",
                steps,
                "--out",
                s(out),
            ]);
        };
        run(&a, "6");
        run(&b, "3");
        let ckpt = b.join("checkpoints/checkpoint_00000003.h5");
        ok(&["--restart", s(&ckpt), "--steps", "6", "-q"]);
        let conserved = |d: &Path| std::fs::read_to_string(d.join("conserved.csv")).unwrap();
        assert_eq!(conserved(&a).lines().count(), 7, "{case}");
        assert!(
            conserved(&a) == conserved(&b),
            "{case}: conserved.csv differs"
        );
        let file = "checkpoints/checkpoint_00000006.h5";
        assert_same_state(&read(&a.join(file)), &read(&b.join(file)), case);
    }
}

/// One of our own snapshots (default fields) starts a case: the first line
/// of conserved.csv holds the kinetic and internal energy of the file's
/// particles, summed here from the file.
#[test]
fn our_snapshot_is_read_as_initial_conditions() {
    let dir = scratch("init-ours");
    let first = dir.join("first");
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "-n",
        "8",
        "--steps",
        "4",
        "-q",
        "--snapshot-every-steps",
        "4",
        "--out",
        s(&first),
    ]);
    let file = first.join("snapshots/snapshot_00000004.h5");
    let snap = read(&file);
    let f = |n: &str| snap.field(n).and_then(FieldData::as_f64).unwrap().to_vec();
    let (m, u) = (f("m"), f("u"));
    let (vx, vy, vz) = (f("vx"), f("vy"), f("vz"));
    let e_kin: f64 = (0..m.len())
        .map(|i| 0.5 * m[i] * (vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i]))
        .sum();
    let e_int: f64 = (0..m.len()).map(|i| m[i] * u[i]).sum();
    assert!(e_kin > 0.0, "the blast has started moving");
    let second = dir.join("second");
    ok(&[
        "sedov",
        "--time-steps",
        "global",
        "--init",
        s(&file),
        "--steps",
        "1",
        "-q",
        "--out",
        s(&second),
    ]);
    let text = std::fs::read_to_string(second.join("conserved.csv")).unwrap();
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    // step, t, dt, E_kin, E_int, ...: time starts at 0 again.
    assert_eq!((row[0], row[1]), (1.0, 0.0));
    assert!(
        (row[3] / e_kin - 1.0).abs() < 1e-12,
        "E_kin {} vs {e_kin}",
        row[3]
    );
    assert!(
        (row[4] / e_int - 1.0).abs() < 1e-12,
        "E_int {} vs {e_int}",
        row[4]
    );
}
