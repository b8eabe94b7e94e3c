//! Shared helpers of the end-to-end validation tests: run a case the way
//! `sphexa run` does and return its summary.

use sph_apps::cases::{self, Layout, Scene, SchemeOverrides, Share};
use sph_apps::simulation::{Progress, Stop};
use sph_apps::{Simulation, Summary};
use sph_core::HydroConfig;
use sph_kernels::{FastKernel, KernelChoice};
use std::path::PathBuf;

/// The target directory's `tmp` folder (what Cargo gives integration
/// tests as `CARGO_TARGET_TMPDIR`), found from the test binary's own path
/// (`target/<profile>/deps/<binary>`): tests write nowhere else.
pub fn target_tmp() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let target = exe
        .ancestors()
        .nth(3)
        .expect("the test binary lies in target/<profile>/deps");
    target.join("tmp")
}

/// An empty folder `name` under [`target_tmp`] (emptied if it was there).
pub fn scratch(name: &str) -> PathBuf {
    let dir = target_tmp().join(name);
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Glass (the default kernel) cached under [`target_tmp`], never in the
/// user's cache: the tests pass with `HOME` pointing anywhere.
pub fn layout() -> Layout {
    Layout::Glass {
        kernel: KernelChoice::default(),
        dir: target_tmp().join("glass"),
    }
}

/// The scene of `case` at `side` particles per side with its own scheme
/// changed by `overrides`, glass from [`layout`].
pub fn scene_with(case: &str, side: usize, overrides: &SchemeOverrides) -> Scene {
    cases::lookup(case)
        .expect("a registered case")
        .setup_share(
            side,
            HydroConfig::default(),
            overrides,
            Share::WHOLE,
            &layout(),
        )
        .unwrap_or_else(|e| panic!("{case} at side {side}: {e}"))
}

/// The scene of `case` at `side` particles per side with its own scheme.
pub fn scene(case: &str, side: usize) -> Scene {
    scene_with(case, side, &SchemeOverrides::default())
}

/// Runs `scene` with the default kernel until `stop`, writing outputs into
/// `out`, and returns the summary.
pub fn run(scene: Scene, stop: Stop, out: &std::path::Path) -> Summary {
    let kernel: FastKernel = KernelChoice::default().fast().expect("default kernel");
    let mut sim = Simulation::new(scene, kernel, KernelChoice::default().to_string())
        .expect("simulation set-up");
    sim.run_serial(stop, out, Progress::Quiet)
        .expect("run completes")
}

/// As [`run`], also writing `particles.csv` (the final state) to `out`.
pub fn run_writing_particles(scene: Scene, stop: Stop, out: &std::path::Path) -> Summary {
    let kernel: FastKernel = KernelChoice::default().fast().expect("default kernel");
    let mut sim = Simulation::new(scene, kernel, KernelChoice::default().to_string())
        .expect("simulation set-up");
    sim.set_write_particles(true);
    sim.run_serial(stop, out, Progress::Quiet)
        .expect("run completes")
}

/// Columns of `particles.csv` in `dir`, by header name.
pub fn read_particles(dir: &std::path::Path) -> std::collections::HashMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(dir.join("particles.csv")).expect("particles.csv");
    let mut lines = text.lines();
    let names: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    for line in lines {
        for (c, v) in cols.iter_mut().zip(line.split(',')) {
            c.push(v.parse().expect("number"));
        }
    }
    names.into_iter().zip(cols).collect()
}
