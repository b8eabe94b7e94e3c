//! Shared helpers of the end-to-end validation tests: run a case the way
//! `sphexa run` does and return its summary.

use sph_apps::cases::Scene;
use sph_apps::simulation::{Progress, Stop};
use sph_apps::{Simulation, Summary};
use sph_kernels::{KernelChoice, Tabulated};

/// Runs `scene` with the default kernel until `stop`, writing outputs into
/// `out`, and returns the summary.
pub fn run(scene: Scene, stop: Stop, out: &std::path::Path) -> Summary {
    let kernel: Tabulated = KernelChoice::default()
        .tabulate(Tabulated::DEFAULT_POINTS)
        .expect("default kernel");
    let mut sim = Simulation::new(scene, kernel, KernelChoice::default().to_string())
        .expect("simulation set-up");
    sim.run(stop, out, Progress::Quiet).expect("run completes")
}
