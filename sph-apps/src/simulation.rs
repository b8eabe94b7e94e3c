//! `Simulation`: runs a scene's pipeline, times every stage, and writes the
//! run's outputs (`conserved.csv`, `timings.csv`, `profile.csv`,
//! `summary.json`) into the output folder.

use crate::analysis::{self, Bin, L1};
use crate::cases::{Reference, Scene};
use crate::AppError;
use serde::Serialize;
use sph_core::{Conserved, Hydro, StepReport, STAGES};
use sph_kernels::Tabulated;
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// When a run stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stop {
    /// After this many steps.
    Steps(u64),
    /// When the time reaches this value (the last step is shortened).
    Time(f64),
}

/// How a run reports progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// A bar when stderr is a terminal, log lines otherwise.
    Auto,
    /// Nothing.
    Quiet,
}

/// Everything the summary holds; written as `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Case name.
    pub case: String,
    /// Particle count.
    pub particles: usize,
    /// Steps run.
    pub steps: u64,
    /// Time reached.
    pub t_end: f64,
    /// Wall-clock seconds of the whole loop.
    pub wall_s: f64,
    /// Mean seconds per step over steps 2..N (step 1 holds set-up).
    pub mean_step_s: f64,
    /// particles / mean_step_s.
    pub particle_steps_per_s: f64,
    /// Peak resident memory of the process.
    pub peak_rss_bytes: u64,
    /// Particle arrays + neighbour lists + tree and scratch buffers, per particle.
    pub bytes_per_particle: f64,
    /// Worker threads.
    pub threads: usize,
    /// Kernel used.
    pub kernel: String,
    /// Mean neighbour count of the last step (self included).
    pub neighbors_mean: f64,
    /// Mean seconds per stage over steps 2..N.
    pub stage_seconds: std::collections::BTreeMap<String, f64>,
    /// L1 errors against the reference (if any).
    pub l1: Option<L1>,
    /// (E_end - E_0) / |E_0|.
    pub energy_rel_drift: f64,
    /// |p_end - p_0| / sum m |v| (a scale for round-off).
    pub momentum_rel_drift: f64,
    /// |L_end - L_0| / |L_0| (or over sum m |x||v| when L_0 ~ 0).
    pub angular_momentum_rel_drift: f64,
    /// Measured shock radius (densest radial bin), blast cases.
    pub shock_radius: Option<f64>,
    /// Reference shock radius.
    pub shock_radius_ref: Option<f64>,
    /// Highest particle density.
    pub peak_density: f64,
    /// Mean density in the post-shock plateau (Noh).
    pub plateau_density: Option<f64>,
    /// Expected plateau density (Noh: 64 rho0).
    pub plateau_density_ref: Option<f64>,
    /// Closest particle pair (square patch).
    pub min_pair_distance: f64,
    /// Initial and final angular momentum z (square patch).
    pub angular_momentum_z: [f64; 2],
    /// Energy updates that fell back to first order.
    pub energy_fallbacks: usize,
}

/// A run in progress: the scene's particles and the pipeline.
#[derive(Debug)]
pub struct Simulation {
    scene: Scene,
    hydro: Hydro<Tabulated>,
    kernel_name: String,
}

impl Simulation {
    /// Assembles the pipeline the scene needs with the given kernel table.
    pub fn new(scene: Scene, kernel: Tabulated, kernel_name: String) -> Result<Self, AppError> {
        let mut scene = scene;
        let hydro = Hydro::new(kernel, scene.config, 0.0, scene.dt0)?;
        hydro.prepare(&mut scene.particles);
        Ok(Self {
            scene,
            hydro,
            kernel_name,
        })
    }

    /// The scene (particles at the current state).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Runs until `stop`, writing outputs into `out` (created if needed).
    pub fn run(&mut self, stop: Stop, out: &Path, progress: Progress) -> Result<Summary, AppError> {
        std::fs::create_dir_all(out).map_err(|e| AppError::io(out, e))?;
        let mut conserved_csv = CsvFile::create(&out.join("conserved.csv"))?;
        conserved_csv
            .line("step,t,dt,E_kin,E_int,E_tot,px,py,pz,Lx,Ly,Lz,nc_min,nc_max,nc_mean")?;
        let mut timings_csv = CsvFile::create(&out.join("timings.csv"))?;
        timings_csv.line(&format!("step,{},total", STAGES.join(",")))?;

        let n = self.scene.particles.len();
        let bar = ProgressReporter::new(progress, stop);
        let start = Instant::now();
        let mut first: Option<Conserved> = None;
        let mut stage_sum = [0.0; 9];
        let mut timed_steps = 0u64;
        let mut fallbacks = 0;
        let mut last_report: Option<StepReport> = None;
        loop {
            let t = self.hydro.time();
            let steps = self.hydro.steps();
            match stop {
                Stop::Steps(s) if steps >= s => break,
                Stop::Time(te) if t >= te * (1.0 - 1e-12) => break,
                _ => {}
            }
            if let Stop::Time(te) = stop {
                self.hydro.limit_next_dt(te - t);
            }
            let r = self
                .hydro
                .step(&mut self.scene.particles, &mut self.scene.bbox)?;
            first.get_or_insert(r.conserved);
            if r.step >= 2 {
                for k in 0..9 {
                    stage_sum[k] += r.times.0[k];
                }
                timed_steps += 1;
            }
            fallbacks += r.energy_fallbacks;
            let c = &r.conserved;
            conserved_csv.line(&format!(
                "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{},{},{:.6}",
                r.step, r.t, r.dt, c.e_kin, c.e_int, c.e_tot(),
                c.momentum[0], c.momentum[1], c.momentum[2],
                c.angular_momentum[0], c.angular_momentum[1], c.angular_momentum[2],
                r.neighbors.min_count, r.neighbors.max_count,
                r.neighbors.total as f64 / n.max(1) as f64
            ))?;
            let times: Vec<String> = r.times.0.iter().map(|s| format!("{s:.6e}")).collect();
            timings_csv.line(&format!(
                "{},{},{:.6e}",
                r.step,
                times.join(","),
                r.times.total()
            ))?;
            bar.update(&r, self.hydro.time());
            last_report = Some(r);
        }
        let wall_s = start.elapsed().as_secs_f64();
        bar.finish();
        conserved_csv.flush()?;
        timings_csv.flush()?;

        // Observables at the final state.
        let t_end = self.hydro.time();
        self.hydro
            .evaluate_density(&mut self.scene.particles, &mut self.scene.bbox)?;
        let p = &self.scene.particles;
        let end = Conserved::compute(p, n);
        let first = first.unwrap_or(end);
        let mean_step_s = if timed_steps > 0 {
            stage_sum.iter().sum::<f64>() / timed_steps as f64
        } else {
            last_report.map_or(f64::NAN, |r| r.times.total())
        };
        let mut stage_seconds = std::collections::BTreeMap::new();
        for (k, name) in STAGES.iter().enumerate() {
            stage_seconds.insert(name.to_string(), stage_sum[k] / timed_steps.max(1) as f64);
        }
        // Last row: the mean over steps 2..N (step 1 holds set-up costs).
        let means: Vec<String> = stage_sum
            .iter()
            .map(|s| format!("{:.6e}", s / timed_steps.max(1) as f64))
            .collect();
        timings_csv.line(&format!("mean_2..N,{},{mean_step_s:.6e}", means.join(",")))?;
        timings_csv.flush()?;
        let reference = self.scene.reference.clone();
        // Radial bins out to the half-width of the (final) box, which every
        // case centres on the origin.
        let [lx, ly, lz] = self.scene.bbox.lengths();
        let r_max = 0.5 * lx.max(ly).max(lz);
        let bins = analysis::radial_profile(p, reference.as_ref(), t_end, r_max, 100);
        write_profile(&out.join("profile.csv"), &bins)?;
        let title = format!("{}, {n} particles, t = {t_end:.4}", self.scene.case);
        crate::plot::profile_png(&out.join("profile.png"), &title, &bins)?;
        let (shock_radius, shock_radius_ref, plateau, plateau_ref) = match &reference {
            Some(Reference::Sedov(s)) => (
                Some(analysis::peak_radius(&bins)),
                Some(s.shock_radius(t_end)),
                None,
                None,
            ),
            Some(Reference::Noh(nh)) => {
                let rs = nh.shock_radius(t_end);
                (
                    None,
                    Some(rs),
                    Some(analysis::mean_density_in_shell(p, 0.3 * rs, 0.8 * rs)),
                    Some(nh.shocked_density()),
                )
            }
            None => (None, None, None, None),
        };
        let scale_p: f64 = (0..n)
            .map(|i| p.m[i] * (p.vx[i].hypot(p.vy[i]).hypot(p.vz[i])))
            .sum();
        let dp = (0..3)
            .map(|k| (end.momentum[k] - first.momentum[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let l0 = first.angular_momentum;
        let dl = (0..3)
            .map(|k| (end.angular_momentum[k] - l0[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let l0n = (l0[0] * l0[0] + l0[1] * l0[1] + l0[2] * l0[2]).sqrt();
        // A scale for round-off: sum m |x||v| (at the end), unless the
        // initial angular momentum is itself significant.
        let l_abs: f64 = (0..n)
            .map(|i| {
                p.m[i] * p.x[i].hypot(p.y[i]).hypot(p.z[i]) * p.vx[i].hypot(p.vy[i]).hypot(p.vz[i])
            })
            .sum();
        let l_scale = if l0n > 1e-6 * l_abs { l0n } else { l_abs };
        let summary = Summary {
            case: self.scene.case.to_string(),
            particles: n,
            steps: self.hydro.steps(),
            t_end,
            wall_s,
            mean_step_s,
            particle_steps_per_s: n as f64 / mean_step_s,
            peak_rss_bytes: analysis::peak_rss_bytes(),
            bytes_per_particle: (p.bytes_per_particle() * n + self.hydro.buffer_bytes()) as f64
                / n.max(1) as f64,
            threads: rayon::current_num_threads(),
            kernel: self.kernel_name.clone(),
            neighbors_mean: last_report.map_or(0.0, |r| r.neighbors.total as f64 / n.max(1) as f64),
            stage_seconds,
            l1: reference.as_ref().map(|rf| analysis::l1(p, rf, t_end)),
            energy_rel_drift: (end.e_tot() - first.e_tot()) / first.e_tot().abs(),
            momentum_rel_drift: if scale_p > 0.0 { dp / scale_p } else { dp },
            angular_momentum_rel_drift: if l_scale > 0.0 { dl / l_scale } else { dl },
            shock_radius,
            shock_radius_ref,
            peak_density: p.rho.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            plateau_density: plateau,
            plateau_density_ref: plateau_ref,
            min_pair_distance: analysis::min_pair_distance(
                p,
                self.hydro.neighbor_list(),
                &self.scene.bbox,
            ),
            angular_momentum_z: [first.angular_momentum[2], end.angular_momentum[2]],
            energy_fallbacks: fallbacks,
        };
        let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
        std::fs::write(out.join("summary.json"), json + "\n").map_err(|e| AppError::io(out, e))?;
        Ok(summary)
    }
}

fn write_profile(path: &Path, bins: &[Bin]) -> Result<(), AppError> {
    let mut f = CsvFile::create(path)?;
    f.line("r,count,rho,p,v,rho_ref,p_ref,v_ref")?;
    for b in bins {
        f.line(&format!(
            "{:.6e},{},{:.8e},{:.8e},{:.8e},{:.8e},{:.8e},{:.8e}",
            b.r, b.count, b.rho, b.p, b.v, b.rho_ref, b.p_ref, b.v_ref
        ))?;
    }
    f.flush()
}

/// A buffered text file that names itself in errors.
struct CsvFile {
    path: PathBuf,
    w: BufWriter<File>,
}

impl CsvFile {
    fn create(path: &Path) -> Result<Self, AppError> {
        let f = File::create(path).map_err(|e| AppError::io(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            w: BufWriter::new(f),
        })
    }

    fn line(&mut self, s: &str) -> Result<(), AppError> {
        writeln!(self.w, "{s}").map_err(|e| AppError::io(&self.path, e))
    }

    fn flush(&mut self) -> Result<(), AppError> {
        self.w.flush().map_err(|e| AppError::io(&self.path, e))
    }
}

/// Progress bar on a terminal, a log line every few seconds otherwise.
struct ProgressReporter {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
    stop: Stop,
    last_log: std::cell::Cell<Instant>,
}

impl ProgressReporter {
    fn new(progress: Progress, stop: Stop) -> Self {
        let quiet = progress == Progress::Quiet;
        let bar = if !quiet && std::io::stderr().is_terminal() {
            let len = match stop {
                Stop::Steps(s) => s,
                Stop::Time(_) => 1000,
            };
            let b = indicatif::ProgressBar::new(len);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {pos}/{len} {msg}",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            Some(b)
        } else {
            None
        };
        Self {
            bar,
            quiet,
            stop,
            last_log: std::cell::Cell::new(Instant::now()),
        }
    }

    fn update(&self, r: &StepReport, t_now: f64) {
        if self.quiet {
            return;
        }
        let msg = format!(
            "step {} t {:.4e} dt {:.3e} E {:.6e} neighbours {}..{}",
            r.step,
            t_now,
            r.dt,
            r.conserved.e_tot(),
            r.neighbors.min_count,
            r.neighbors.max_count
        );
        if let Some(b) = &self.bar {
            match self.stop {
                Stop::Steps(_) => b.set_position(r.step),
                Stop::Time(te) => b.set_position((t_now / te * 1000.0).min(1000.0) as u64),
            }
            b.set_message(msg);
        } else if self.last_log.get().elapsed().as_secs_f64() > 5.0 || r.step == 1 {
            self.last_log.set(Instant::now());
            eprintln!("{msg}");
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish();
        }
    }
}
