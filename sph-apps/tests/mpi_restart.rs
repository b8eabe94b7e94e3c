//! Checkpoints across rank counts (built only with `--features mpi`; run by
//! `cargo test -p sph-apps --features mpi --test mpi_restart`): a Sedov run
//! on 2 ranks writes a checkpoint at step 10 and a snapshot at step 20; the
//! checkpoint, restarted on 1 and on 4 ranks, gives the conserved
//! quantities and the step-20 snapshot of the uninterrupted serial run to
//! the bit, and the snapshot written by 2 ranks holds the serial run's
//! particles in the same order; the same for a block-step Sedov run
//! (checkpoint at the synchronisation point of sub-step 44, snapshot at
//! 55).

mod common;

use sph_io::{H5Part, Selection, Snapshot, SnapshotReader};
use std::path::{Path, PathBuf};

fn mpirun(ranks: usize, args: &[&str]) {
    let mut c = sph_comm::launch::mpirun(ranks).unwrap_or_else(|e| panic!("{e}"));
    c.env("SPHEXA_GLASS_DIR", common::glass_dir());
    c.arg(env!("CARGO_BIN_EXE_sphexa")).arg("run").args(args);
    let out = c.output().expect("mpirun runs");
    assert!(
        out.status.success(),
        "mpirun -n {ranks} sphexa run {args:?} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn read(path: &Path) -> Snapshot {
    let mut s = H5Part
        .read_step(path, 0, &Selection::All)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    s.attrs.retain(|(n, _)| n != "config");
    s
}

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// The lines of `conserved.csv` of steps after `step` (one per step of a
/// global run; one per synchronisation point under block time steps).
fn lines_after(path: &Path, step: usize) -> Vec<String> {
    std::fs::read_to_string(path.join("conserved.csv"))
        .expect("conserved.csv")
        .lines()
        .skip(1)
        .filter(|l| {
            l.split(',')
                .next()
                .and_then(|s| s.parse::<usize>().ok())
                .is_some_and(|k| k > step)
        })
        .map(str::to_owned)
        .collect()
}

#[test]
fn written_on_two_ranks_restarted_on_one_and_four() {
    // Sedov, and turbulence: its driving state (OU phases, generator,
    // work) continues from the checkpoint too.
    for case in ["sedov", "turbulence"] {
        restarted_on_one_and_four(case, &["--time-steps", "global"], [10, 20]);
    }
    // Block time steps (the case's default): the checkpoint falls due at
    // sub-step 10 and is written at a later synchronisation point (sub-step
    // 47 under `best`, with the longest step pinned to an eighth of the
    // span); the time line (tick, span, longest bin, the start ramp), the
    // held fields and the switches continue from it.
    restarted_on_one_and_four(
        "sedov",
        &[
            "--time-steps",
            "block",
            "--dt-max",
            "0.00625",
            "--scheme",
            "best",
        ],
        [47, 55],
    );
}

/// `case` with `options` for `steps[1]` steps on 1 and 2 ranks, a
/// checkpoint due every 10 steps and a snapshot at `steps[1]`; the
/// 2-rank checkpoint of step `steps[0]` restarted on 1 and 4 ranks.
fn restarted_on_one_and_four(case: &str, options: &[&str], [at, steps]: [usize; 2]) {
    let label = format!("{case}{}", options.join(""));
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("mpi-restart-{label}"));
    std::fs::remove_dir_all(&root).ok();
    let dir = |n: &str| root.join(n).to_str().expect("UTF-8").to_owned();
    let steps_s = steps.to_string();
    let common = [
        case,
        "-n",
        "16",
        "-q",
        "--threads",
        "1",
        "--checkpoint-every",
        "10",
        "--snapshot-every-steps",
        &steps_s,
    ];
    let with = |out: &str, extra: &[&str]| {
        let mut v: Vec<String> = common.iter().map(|s| s.to_string()).collect();
        v.extend(options.iter().map(|s| s.to_string()));
        v.extend(["--out".into(), out.to_owned()]);
        if case == "turbulence" {
            // Spectra too: a fixed-point deposit reduced over the ranks.
            v.extend(["--spectra-every-time".into(), "0.001".into()]);
        }
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    mpirun(1, &refs(&with(&dir("serial"), &["--steps", &steps_s])));
    mpirun(2, &refs(&with(&dir("two"), &["--steps", &steps_s])));
    let ckpt = root.join(format!("two/checkpoints/checkpoint_{at:08}.h5"));
    let ckpt = ckpt.to_str().expect("UTF-8");
    for ranks in [1, 4] {
        let out = dir(&format!("restart-{ranks}"));
        mpirun(
            ranks,
            &["--restart", ckpt, "--steps", &steps_s, "--out", &out],
        );
    }
    let serial = root.join("serial");
    let want_lines = lines_after(&serial, at);
    if options.contains(&"global") {
        assert_eq!(want_lines.len(), steps - at, "{label}");
    } else {
        // Block steps: a row at each synchronisation point after it.
        assert!(!want_lines.is_empty(), "{label}: no row after step {at}");
    }
    let snapshot = format!("snapshots/snapshot_{steps:08}.h5");
    let want = read(&serial.join(&snapshot));
    assert_eq!(want.len(), 4096);
    let two = read(&root.join("two").join(&snapshot));
    assert!(
        two.bits_eq(&want),
        "{label}: the 2-rank snapshot differs from the serial one"
    );
    assert_eq!(lines_after(&root.join("two"), 0), lines_after(&serial, 0));
    if case == "turbulence" {
        let spectra = |d: &str| -> Vec<(String, Vec<u8>)> {
            let mut files: Vec<_> = std::fs::read_dir(root.join(d).join("spectra"))
                .expect("spectra written")
                .map(|e| {
                    let p = e.expect("entry").path();
                    let name = p.file_name().unwrap().to_string_lossy().to_string();
                    (name, std::fs::read(&p).expect("readable"))
                })
                .collect();
            files.sort();
            files
        };
        let one = spectra("serial");
        assert!(
            one.len() >= 4,
            "spectra: {:?}",
            one.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        assert!(
            spectra("two") == one,
            "the 2-rank spectra differ from the serial ones"
        );
    }
    for ranks in [1, 4] {
        let d = root.join(format!("restart-{ranks}"));
        assert_eq!(
            lines_after(&d, 0),
            want_lines,
            "{label}, {ranks} ranks: conserved.csv"
        );
        let got = read(&d.join(&snapshot));
        assert!(
            got.bits_eq(&want),
            "{label}, {ranks} ranks: the step-{steps} snapshot differs"
        );
    }
}

/// Initial conditions from files on several ranks, each rank reading its
/// share: an SPH-EXA-layout file (no checksums) and one of our snapshots
/// give on 2 ranks the conserved quantities of the serial run (global
/// steps: a row per step).
#[test]
fn initial_conditions_from_files_on_two_ranks() {
    use hdf5_pure::AttrValue;
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mpi-init");
    std::fs::remove_dir_all(&root).ok();
    std::fs::create_dir_all(&root).unwrap();
    let scene = sph_apps::cases::lookup("sedov")
        .unwrap()
        .setup(12, sph_core::HydroConfig::default())
        .unwrap();
    let p = &scene.particles;
    let attrs = [
        ("time", AttrValue::F64(0.0)),
        (
            "box",
            AttrValue::F64Array(vec![-0.5, 0.5, -0.5, 0.5, -0.5, 0.5]),
        ),
    ];
    let fields: [(&str, &[f64]); 6] = [
        ("x", &p.x),
        ("y", &p.y),
        ("z", &p.z),
        ("h", &p.h),
        ("m", &p.m),
        ("u", &p.u),
    ];
    let foreign = root.join("sphexa.h5");
    common::write_sphexa_file(&foreign, &attrs, &fields);
    let dir = |n: &str| root.join(n).to_str().expect("UTF-8").to_owned();
    let conserved = |n: &str| std::fs::read_to_string(root.join(n).join("conserved.csv")).unwrap();
    let foreign = foreign.to_str().unwrap();
    for ranks in [1, 2] {
        let out = dir(&format!("foreign-{ranks}"));
        mpirun(
            ranks,
            &[
                "sedov",
                "--time-steps",
                "global",
                "--init",
                foreign,
                "--steps",
                "5",
                "-q",
                "--threads",
                "1",
                "--snapshot-every-steps",
                "5",
                "--out",
                &out,
            ],
        );
    }
    assert_eq!(conserved("foreign-1").lines().count(), 6);
    assert_eq!(conserved("foreign-1"), conserved("foreign-2"));
    let ours = root.join("foreign-2/snapshots/snapshot_00000005.h5");
    let ours = ours.to_str().unwrap();
    for ranks in [1, 2] {
        let out = dir(&format!("ours-{ranks}"));
        mpirun(
            ranks,
            &[
                "sedov",
                "--time-steps",
                "global",
                "--init",
                ours,
                "--steps",
                "3",
                "-q",
                "--threads",
                "1",
                "--out",
                &out,
            ],
        );
    }
    assert_eq!(conserved("ours-1").lines().count(), 4);
    assert_eq!(conserved("ours-1"), conserved("ours-2"));
}
