//! `Simulation`: runs a scene's pipeline, times every stage, and writes the
//! run's outputs (`conserved.csv`, `timings.csv`, `profile.csv`,
//! `summary.json`) into the output folder.

use crate::analysis::{self, Bin, L1};
use crate::cases::{Reference, Scene};
use crate::AppError;
use serde::Serialize;
use sph_comm::{Communicator, ReduceOp, SerialComm};
use sph_core::{Conserved, FieldSet, Hydro, Particles, StepReport, STAGES};
use sph_domain::DomainConfig;
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
    /// MPI ranks (1 for a serial run).
    pub ranks: usize,
    /// Decomposition figures, means over steps 2..N.
    pub domain: DomainSummary,
    /// Energies against the case's reference table (times up to t_end;
    /// the run's values interpolated linearly between steps).
    pub energies: Vec<EnergyCheck>,
}

/// The run's energies at a reference time, beside the reference values.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct EnergyCheck {
    /// Time.
    pub t: f64,
    /// Kinetic energy of the run.
    pub e_kin: f64,
    /// Internal energy of the run.
    pub e_int: f64,
    /// Gravitational energy of the run.
    pub e_grav: f64,
    /// Reference kinetic energy.
    pub e_kin_ref: f64,
    /// Reference internal energy.
    pub e_int_ref: f64,
    /// Reference gravitational energy.
    pub e_grav_ref: f64,
}

/// `[E_kin, E_int, E_grav]` at `t`, linear between the samples `[t, ...]`
/// (sorted by t).
fn interpolate(samples: &[[f64; 4]], t: f64) -> [f64; 3] {
    let k = samples.partition_point(|s| s[0] < t);
    if k == 0 {
        return [samples[0][1], samples[0][2], samples[0][3]];
    }
    if k == samples.len() {
        let s = samples[k - 1];
        return [s[1], s[2], s[3]];
    }
    let (a, b) = (samples[k - 1], samples[k]);
    let w = if b[0] > a[0] {
        (t - a[0]) / (b[0] - a[0])
    } else {
        1.0
    };
    std::array::from_fn(|j| a[j + 1] + w * (b[j + 1] - a[j + 1]))
}

/// Energies against time with the reference values as markers.
fn write_energy_plot(
    path: &Path,
    title: &str,
    samples: &[[f64; 4]],
    reference: &[crate::cases::EnergyPoint],
) -> Result<(), AppError> {
    use plotters::style::RGBColor;
    let pick = |f: fn(&[f64; 4]) -> f64| -> Vec<(f64, f64)> {
        samples.iter().map(|s| (s[0], f(s))).collect()
    };
    let kin = pick(|s| s[1]);
    let int = pick(|s| s[2]);
    let grav = pick(|s| s[3]);
    let tot = pick(|s| s[1] + s[2] + s[3]);
    let colours = [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(0, 0, 0),
    ];
    let rk: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_kin)).collect();
    let ri: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_int)).collect();
    let rg: Vec<(f64, f64)> = reference.iter().map(|e| (e.t, e.e_grav)).collect();
    crate::plot::energy_png(
        path,
        title,
        &[
            ("E_kin", colours[0], &kin),
            ("E_int", colours[1], &int),
            ("E_grav", colours[2], &grav),
            ("E_tot", colours[3], &tot),
        ],
        &[
            ("E_kin ref", colours[0], &rk),
            ("E_int ref", colours[1], &ri),
            ("E_grav ref", colours[2], &rg),
        ],
    )
}

/// Decomposition figures of a run (means over steps 2..N).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct DomainSummary {
    /// Fewest particles on a rank (last step).
    pub owned_min: usize,
    /// Most particles on a rank (last step).
    pub owned_max: usize,
    /// Mean over steps of total halos / total owned.
    pub halo_ratio_mean: f64,
    /// Mean over steps of the largest halos / owned of a rank.
    pub halo_ratio_max: f64,
    /// Mean bytes sent per step, all ranks together.
    pub bytes_sent_per_step: f64,
    /// Mean over steps of the longest per-rank time in domain communication.
    pub comm_seconds_per_step: f64,
    /// Mean over steps of the longest per-rank time in `sync`.
    pub sync_seconds_per_step: f64,
}

/// A run in progress: the scene's particles (this rank's share) and the
/// pipeline.
#[derive(Debug)]
pub struct Simulation<C: Communicator = SerialComm> {
    scene: Scene,
    hydro: Hydro<Tabulated, C>,
    kernel_name: String,
    total: usize,
    write_particles: bool,
}

impl Simulation {
    /// Assembles the serial pipeline the scene needs with the given kernel
    /// table.
    pub fn new(scene: Scene, kernel: Tabulated, kernel_name: String) -> Result<Self, AppError> {
        Simulation::with_comm(scene, kernel, kernel_name, SerialComm::new())
    }
}

impl<C: Communicator> Simulation<C> {
    /// Assembles the pipeline on one rank of `comm`. Every rank passes the
    /// whole scene and keeps a contiguous share of its particles; the first
    /// step migrates them to their owners.
    pub fn with_comm(
        scene: Scene,
        kernel: Tabulated,
        kernel_name: String,
        comm: C,
    ) -> Result<Self, AppError> {
        let mut scene = scene;
        let total = scene.particles.len();
        let (rank, size) = (comm.rank(), comm.size());
        scene
            .particles
            .keep(total * rank / size..total * (rank + 1) / size);
        let hydro = Hydro::with_comm(
            kernel,
            scene.config,
            0.0,
            scene.dt0,
            comm,
            DomainConfig::default(),
        )?;
        hydro.prepare(&mut scene.particles);
        Ok(Self {
            scene,
            hydro,
            kernel_name,
            total,
            write_particles: false,
        })
    }

    /// The scene (this rank's particles at the current state, halos
    /// included after a step: see [`Simulation::owned`]).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Range of this rank's own particles in the scene's arrays.
    pub fn owned(&self) -> std::ops::Range<usize> {
        self.hydro.owned()
    }

    /// Whether this rank writes the outputs (rank 0).
    pub fn is_root(&self) -> bool {
        self.hydro.domain().comm().rank() == 0
    }

    /// Every rank's owned particles, sorted by id, on every rank (for
    /// observables and state dumps): id, position, velocity, h, m, u, rho,
    /// P and, with self-gravity, phi.
    pub fn gather(&self) -> Result<Particles, AppError> {
        let p = &self.scene.particles;
        let gravity = !p.phi.is_empty();
        let fields: Vec<&[f64]> = [
            &p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.h, &p.m, &p.u, &p.rho, &p.p, &p.phi,
        ]
        .into_iter()
        .filter(|f| !f.is_empty())
        .map(|f| f.as_slice())
        .collect();
        let words = 1 + fields.len();
        let owned = self.hydro.owned();
        let mut send = Vec::with_capacity(owned.len() * words);
        for i in owned {
            send.push(p.id[i]);
            send.extend(fields.iter().map(|f| f[i].to_bits()));
        }
        let all = self.hydro.domain().comm().all_gather_v(&send)?;
        let mut rows: Vec<&[u64]> = all.data.chunks_exact(words).collect();
        rows.sort_unstable_by_key(|r| r[0]);
        let mut g = Particles::new(
            rows.len(),
            FieldSet {
                iad: false,
                grad_h: false,
                gravity,
            },
        );
        for (k, r) in rows.iter().enumerate() {
            g.id[k] = r[0];
            let mut dst: Vec<&mut Vec<f64>> = vec![
                &mut g.x, &mut g.y, &mut g.z, &mut g.vx, &mut g.vy, &mut g.vz, &mut g.h, &mut g.m,
                &mut g.u, &mut g.rho, &mut g.p,
            ];
            if gravity {
                dst.push(&mut g.phi);
            }
            for (d, &w) in dst.into_iter().zip(&r[1..]) {
                d[k] = f64::from_bits(w);
            }
        }
        Ok(g)
    }

    /// Also write the final state of every particle (`particles.csv`,
    /// sorted by id, shortest round-trip decimals: the exact bits).
    pub fn set_write_particles(&mut self, on: bool) {
        self.write_particles = on;
    }

    /// Runs until `stop`, writing outputs into `out` (created if needed; by
    /// rank 0 alone).
    pub fn run(&mut self, stop: Stop, out: &Path, progress: Progress) -> Result<Summary, AppError> {
        let root = self.is_root();
        let mut conserved_csv = None;
        let mut timings_csv = None;
        if root {
            std::fs::create_dir_all(out).map_err(|e| AppError::io(out, e))?;
            let mut c = CsvFile::create(&out.join("conserved.csv"))?;
            c.line("step,t,dt,E_kin,E_int,E_grav,E_tot,px,py,pz,Lx,Ly,Lz,nc_min,nc_max,nc_mean")?;
            let mut t = CsvFile::create(&out.join("timings.csv"))?;
            t.line(&format!(
                "step,{},total,owned_min,owned_max,halo_ratio,halo_ratio_max,bytes_sent,comm_s_max,sync_s_max",
                STAGES.join(",")
            ))?;
            conserved_csv = Some(c);
            timings_csv = Some(t);
        }

        let n = self.total;
        let bar = ProgressReporter::new(if root { progress } else { Progress::Quiet }, stop);
        let start = Instant::now();
        let mut first: Option<Conserved> = None;
        let mut stage_sum = [0.0; STAGES.len()];
        let mut dom = DomainSummary::default();
        let mut timed_steps = 0u64;
        let mut fallbacks = 0;
        let mut last_report: Option<StepReport> = None;
        let mut energies: Vec<[f64; 4]> = Vec::new();
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
            let c = &r.conserved;
            energies.push([r.t, c.e_kin, c.e_int, c.e_grav]);
            let d = r.domain;
            let halo_ratio = d.halos_total as f64 / n.max(1) as f64;
            if r.step >= 2 {
                for k in 0..STAGES.len() {
                    stage_sum[k] += r.times.0[k];
                }
                dom.halo_ratio_mean += halo_ratio;
                dom.halo_ratio_max += d.halo_ratio_max;
                dom.bytes_sent_per_step += d.bytes_sent as f64;
                dom.comm_seconds_per_step += d.comm_seconds_max;
                dom.sync_seconds_per_step += d.sync_seconds_max;
                timed_steps += 1;
            }
            (dom.owned_min, dom.owned_max) = (d.owned_min, d.owned_max);
            fallbacks += r.energy_fallbacks;
            let c = &r.conserved;
            if let (Some(cc), Some(tc)) = (conserved_csv.as_mut(), timings_csv.as_mut()) {
                cc.line(&format!(
                    "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{},{},{:.6}",
                    r.step, r.t, r.dt, c.e_kin, c.e_int, c.e_grav, c.e_tot(),
                    c.momentum[0], c.momentum[1], c.momentum[2],
                    c.angular_momentum[0], c.angular_momentum[1], c.angular_momentum[2],
                    r.neighbors.min_count, r.neighbors.max_count,
                    r.neighbors.total as f64 / n.max(1) as f64
                ))?;
                let times: Vec<String> = r.times.0.iter().map(|s| format!("{s:.6e}")).collect();
                tc.line(&format!(
                    "{},{},{:.6e},{},{},{:.6e},{:.6e},{},{:.6e},{:.6e}",
                    r.step,
                    times.join(","),
                    r.times.total(),
                    d.owned_min,
                    d.owned_max,
                    halo_ratio,
                    d.halo_ratio_max,
                    d.bytes_sent,
                    d.comm_seconds_max,
                    d.sync_seconds_max
                ))?;
            }
            bar.update(&r, self.hydro.time());
            last_report = Some(r);
        }
        let wall_s = start.elapsed().as_secs_f64();
        bar.finish();
        if let (Some(cc), Some(tc)) = (conserved_csv.as_mut(), timings_csv.as_mut()) {
            cc.flush()?;
            tc.flush()?;
        }
        let steps_div = timed_steps.max(1) as f64;
        dom.halo_ratio_mean /= steps_div;
        dom.halo_ratio_max /= steps_div;
        dom.bytes_sent_per_step /= steps_div;
        dom.comm_seconds_per_step /= steps_div;
        dom.sync_seconds_per_step /= steps_div;

        // Observables at the final state, from every rank's particles.
        let t_end = self.hydro.time();
        self.hydro
            .evaluate_density(&mut self.scene.particles, &mut self.scene.bbox)?;
        let comm = self.hydro.domain().comm();
        let min_pair2 = comm.all_reduce_scalar(
            analysis::min_pair_distance(
                &self.scene.particles,
                self.hydro.neighbor_list(),
                &self.scene.bbox,
            ),
            ReduceOp::Min,
        );
        let peak_rss = comm.all_reduce_scalar(analysis::peak_rss_bytes(), ReduceOp::Max);
        let local_bytes = (self.scene.particles.bytes_per_particle() * self.hydro.owned().len()
            + self.hydro.buffer_bytes()) as u64;
        let total_bytes = comm.all_reduce_scalar(local_bytes, ReduceOp::Sum);
        let ranks = comm.size();
        let p = &self.gather()?;
        let (end, []) = Conserved::compute(p, 0..p.len(), [], &SerialComm::new());
        energies.push([t_end, end.e_kin, end.e_int, end.e_grav]);
        let energy_check: Vec<EnergyCheck> = self
            .scene
            .energies
            .unwrap_or(&[])
            .iter()
            .filter(|e| e.t <= t_end * (1.0 + 1e-12))
            .map(|e| {
                let at = interpolate(&energies, e.t);
                EnergyCheck {
                    t: e.t,
                    e_kin: at[0],
                    e_int: at[1],
                    e_grav: at[2],
                    e_kin_ref: e.e_kin,
                    e_int_ref: e.e_int,
                    e_grav_ref: e.e_grav,
                }
            })
            .collect();
        let first = first.unwrap_or(end);
        let mean_step_s = if timed_steps > 0 {
            stage_sum.iter().sum::<f64>() / timed_steps as f64
        } else {
            last_report.map_or(f64::NAN, |r| r.times.total())
        };
        let mut stage_seconds = std::collections::BTreeMap::new();
        for (k, name) in STAGES.iter().enumerate() {
            stage_seconds.insert(name.to_string(), stage_sum[k] / steps_div);
        }
        let reference = self.scene.reference.clone();
        // Radial bins out to the half-width of the (final) box, which every
        // case centres on the origin.
        let [lx, ly, lz] = self.scene.bbox.lengths();
        let r_max = 0.5 * lx.max(ly).max(lz);
        let bins = analysis::radial_profile(p, reference.as_ref(), t_end, r_max, 100);
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
            peak_rss_bytes: peak_rss,
            bytes_per_particle: total_bytes as f64 / n.max(1) as f64,
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
            min_pair_distance: min_pair2,
            angular_momentum_z: [first.angular_momentum[2], end.angular_momentum[2]],
            energy_fallbacks: fallbacks,
            ranks,
            domain: dom,
            energies: energy_check,
        };
        if root {
            // Last row: the mean over steps 2..N (step 1 holds set-up costs).
            let means: Vec<String> = stage_sum
                .iter()
                .map(|s| format!("{:.6e}", s / steps_div))
                .collect();
            if let Some(tc) = timings_csv.as_mut() {
                tc.line(&format!(
                    "mean_2..N,{},{mean_step_s:.6e},{},{},{:.6e},{:.6e},{:.0},{:.6e},{:.6e}",
                    means.join(","),
                    dom.owned_min,
                    dom.owned_max,
                    dom.halo_ratio_mean,
                    dom.halo_ratio_max,
                    dom.bytes_sent_per_step,
                    dom.comm_seconds_per_step,
                    dom.sync_seconds_per_step
                ))?;
                tc.flush()?;
            }
            write_profile(&out.join("profile.csv"), &bins)?;
            if self.scene.config.gravity.is_some() || self.scene.energies.is_some() {
                write_energy_plot(
                    &out.join("energies.png"),
                    &format!("{}, {n} particles", self.scene.case),
                    &energies,
                    self.scene.energies.unwrap_or(&[]),
                )?;
            }
            let title = format!("{}, {n} particles, t = {t_end:.4}", self.scene.case);
            crate::plot::profile_png(&out.join("profile.png"), &title, &bins)?;
            if self.write_particles {
                write_particles(&out.join("particles.csv"), p)?;
            }
            let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
            std::fs::write(out.join("summary.json"), json + "\n")
                .map_err(|e| AppError::io(out, e))?;
        }
        Ok(summary)
    }
}

/// The state of every particle, one row per particle in id order; floats in
/// Rust's shortest round-trip form, so the file holds the exact bits.
fn write_particles(path: &Path, p: &Particles) -> Result<(), AppError> {
    let mut f = CsvFile::create(path)?;
    f.line("id,x,y,z,vx,vy,vz,h,m,u,rho,p")?;
    for i in 0..p.len() {
        f.line(&format!(
            "{},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            p.id[i],
            p.x[i],
            p.y[i],
            p.z[i],
            p.vx[i],
            p.vy[i],
            p.vz[i],
            p.h[i],
            p.m[i],
            p.u[i],
            p.rho[i],
            p.p[i]
        ))?;
    }
    f.flush()
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
