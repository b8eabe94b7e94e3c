//! Shared helpers of the end-to-end validation tests: run a case the way
//! `sphexa run` does and return its summary.

use sph_apps::cases::Scene;
use sph_apps::simulation::{Progress, Stop};
use sph_apps::{Simulation, Summary};
use sph_kernels::{FastKernel, KernelChoice};

/// Runs `scene` with the default kernel until `stop`, writing outputs into
/// `out`, and returns the summary.
pub fn run(scene: Scene, stop: Stop, out: &std::path::Path) -> Summary {
    let kernel: FastKernel = KernelChoice::default().fast().expect("default kernel");
    let mut sim = Simulation::new(scene, kernel, KernelChoice::default().to_string())
        .expect("simulation set-up");
    sim.run(stop, out, Progress::Quiet).expect("run completes")
}

/// As [`run`], also writing `particles.csv` (the final state) to `out`.
pub fn run_writing_particles(scene: Scene, stop: Stop, out: &std::path::Path) -> Summary {
    let kernel: FastKernel = KernelChoice::default().fast().expect("default kernel");
    let mut sim = Simulation::new(scene, kernel, KernelChoice::default().to_string())
        .expect("simulation set-up");
    sim.set_write_particles(true);
    sim.run(stop, out, Progress::Quiet).expect("run completes")
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
