//! What the integration tests of `sphexa` share: the binary with its glass
//! cache under the target directory, fresh scratch folders there, and the
//! checks of a run that must succeed or be refused.

// Every test file uses its own subset of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The glass cache of every `sphexa` a test starts: under the target
/// directory, never the user's cache, and shared by the tests so that a
/// glass is relaxed once (the cache stores it under a unique name first,
/// so parallel tests may fill it at once).
pub fn glass_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sphexa-glass-cache")
}

/// The `sphexa` binary, its glass cache set to [`glass_dir`].
pub fn sphexa_command() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sphexa"));
    c.env("SPHEXA_GLASS_DIR", glass_dir());
    c
}

/// Runs `sphexa ARGS` to the end.
pub fn sphexa(args: &[&str]) -> Output {
    sphexa_command()
        .args(args)
        .output()
        .expect("the sphexa binary runs")
}

/// A fresh, empty folder `NAME` of this test file (`restart-NAME` for
/// tests/restart.rs) under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("{}-{name}", env!("CARGO_CRATE_NAME")));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// A path as the `&str` an argument list takes.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// Runs `sphexa run ARGS` and expects success.
pub fn ok(args: &[&str]) {
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    let out = sphexa(&all);
    assert!(
        out.status.success(),
        "sphexa {all:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `sphexa run ARGS`, expects a refusal without a panic, and returns
/// stderr.
pub fn refused(args: &[&str]) -> String {
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    let out = sphexa(&all);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success(),
        "sphexa {all:?} succeeded; stderr: {stderr}"
    );
    assert!(
        !stderr.contains("panicked"),
        "sphexa {all:?} panicked: {stderr}"
    );
    stderr
}

/// Asserts that `stderr` contains every one of `words`.
pub fn assert_mentions(stderr: &str, words: &[&str]) {
    for w in words {
        assert!(stderr.contains(w), "stderr lacks {w:?}:\n{stderr}");
    }
}

/// Writes an H5Part file in SPH-EXA's layout, as another code would: one
/// group `Step#0` with the step attributes `attrs` and one 1-D `f64`
/// dataset per field (no ids, no checksums, no field table).
pub fn write_sphexa_file(
    path: &Path,
    attrs: &[(&str, hdf5_pure::AttrValue)],
    fields: &[(&str, &[f64])],
) {
    let mut b = hdf5_pure::FileBuilder::new();
    let mut g = b.create_group("Step#0");
    for (k, v) in attrs {
        g.set_attr(k, v.clone());
    }
    for (name, v) in fields {
        g.create_dataset(name).with_f64_data(v);
    }
    b.add_group(g.finish());
    std::fs::write(path, b.finish().expect("an HDF5 image")).expect("the file is written");
}

/// The fields of an initial state by SPH-EXA's names: positions,
/// velocities, smoothing lengths, masses, internal energies.
pub fn initial_fields(p: &sph_core::Particles) -> [(&'static str, &[f64]); 9] {
    [
        ("x", &p.x),
        ("y", &p.y),
        ("z", &p.z),
        ("vx", &p.vx),
        ("vy", &p.vy),
        ("vz", &p.vz),
        ("h", &p.h),
        ("m", &p.m),
        ("u", &p.u),
    ]
}
