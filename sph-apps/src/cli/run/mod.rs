//! `sphexa run`: the run's options (layered with `--config` and
//! `--restart`), its case, scheme and initial particles, then the
//! [`Simulation`] and its summary on the terminal.

pub(crate) mod args;
mod layers;
mod resolved;
pub(crate) mod scheme;
mod scheme_args;

use crate::cli::parse::CheckpointSpec;
use crate::cli::start_threads;
use crate::output::snapshot::{self as snapfile, Schedule};
use crate::simulation::{CheckpointEvery, Outputs, Progress, SnapshotFormat, Stop};
use crate::watch::{Bounds, Watch};
use crate::{cases, checkpoint, AppError, Simulation};
use args::{CurveArg, FormatArg, RunArgs, DEFAULT_MOMENTUM_BOUND};
use clap::ArgMatches;
use sph_comm::Communicator;
use sph_core::{HydroConfig, TimeSteps};
use sph_kernels::FastKernel;
use sph_tree::Curve;
use std::path::PathBuf;

/// `sphexa run`: the options `a` (as parsed into `m`) over the layers of
/// `--config` and `--restart`, then the run.
pub(crate) fn run(a: RunArgs, m: &ArgMatches) -> Result<(), AppError> {
    layers::layered(a, m).and_then(execute)
}

/// The snapshot and checkpoint outputs the options ask for; `config` is
/// the resolved configuration (stored in every file), `t0` the start time.
fn outputs(a: &RunArgs, config: String, t0: f64) -> Result<Outputs, AppError> {
    let schedule = Schedule::new(
        a.snapshot_every_steps,
        a.snapshot_every_time,
        a.snapshot_at.clone().map(|t| t.0).unwrap_or_default(),
        t0,
    );
    if a.snapshot_fields.is_some() && !schedule.is_active() {
        return Err(AppError::Usage(
            "--snapshot-fields needs a schedule: --snapshot-every-steps N, --snapshot-every-time T or --snapshot-at T1,T2,...".into(),
        ));
    }
    let snapshots = schedule.is_active().then(|| {
        let fields = a.snapshot_fields.clone().map(|f| f.0).unwrap_or_else(|| {
            snapfile::DEFAULT_FIELDS
                .iter()
                .map(|s| (*s).to_owned())
                .collect()
        });
        (fields, schedule)
    });
    let every = match (a.checkpoint_every, a.mtbf) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(AppError::Usage("--mtbf is used by --checkpoint-every auto; give both".into()))
        }
        (Some(CheckpointSpec::Auto), None) => {
            return Err(AppError::Usage(
                "--checkpoint-every auto needs --mtbf DURATION (the machine's mean time between failures, e.g. 6h)".into(),
            ))
        }
        (Some(CheckpointSpec::Auto), Some(m)) => Some(CheckpointEvery::Auto { mtbf_s: m }),
        (Some(_), Some(_)) => {
            return Err(AppError::Usage("--mtbf applies only to --checkpoint-every auto".into()))
        }
        (Some(CheckpointSpec::Steps(n)), None) => Some(CheckpointEvery::Steps(n)),
        (Some(CheckpointSpec::Time(t)), None) => Some(CheckpointEvery::Time(t)),
        (Some(CheckpointSpec::Wall(w)), None) => Some(CheckpointEvery::Wall(w)),
    };
    let format = match a.snapshot_format {
        FormatArg::H5part => SnapshotFormat::H5Part,
        FormatArg::Swift if a.snapshot_fields.is_some() => {
            return Err(AppError::Usage(
                "--snapshot-fields chooses the fields of our snapshots; --snapshot-format swift writes SWIFT's fixed set (leave one out)".into(),
            ))
        }
        FormatArg::Swift => {
            let kernel = a
                .kernel
                .exact()
                .map_err(|e| AppError::Usage(format!("--kernel {}: {e}", a.kernel)))?;
            SnapshotFormat::Swift {
                h_per_h: sph_io::swift::swift_h_per_h(|v| kernel.shape(v)),
            }
        }
    };
    Ok(Outputs {
        snapshots,
        checkpoints: every.map(|e| (e, a.checkpoint_keep)),
        attrs: vec![("config".into(), sph_io::Attr::Str(config))],
        format,
        spectra_every_time: a.spectra_every_time,
    })
}

/// The rank count an MPI launcher announces to the processes it starts
/// (Open MPI; MPICH and others through PMI), if any.
#[cfg(not(feature = "mpi"))]
fn launched_ranks() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|k| std::env::var(k).ok()?.trim().parse().ok())
}

/// Refuses the options of a scene of the user's own (`--box`,
/// `--boundary`, `--gravity`) in a run of case `name`, which has its own.
fn refuse_scene_options(a: &RunArgs, name: &str) -> Result<(), AppError> {
    let given = [
        ("--box", a.cube.is_some()),
        ("--boundary", a.boundary.is_some()),
        ("--gravity", a.gravity.is_some()),
    ];
    match given.iter().find(|g| g.1) {
        Some((option, _)) => Err(AppError::Usage(format!(
            "{option} describes a scene of your own (--init FILE without a case); case '{name}' has its own box, boundaries and gravity (see `sphexa cases`)"
        ))),
        None => Ok(()),
    }
}

/// The scene of `source` (the option that names its file, for messages;
/// the file's attributes `file`) with the physics the options `a` give.
/// `--side` has no meaning for it and is refused.
fn user_scene(
    a: &RunArgs,
    source: &str,
    file: &cases::scene::FileAttrs,
) -> Result<cases::scene::UserScene, AppError> {
    if let Some(n) = a.side {
        return Err(AppError::Usage(format!(
            "{source}: --side {n} has no meaning for a scene of your own, whose particles are the file's; leave --side out"
        )));
    }
    let opts = cases::scene::SceneOptions {
        eos: a.eos,
        bbox: a.cube.map(|b| b.0),
        boundary: a.boundary.map(|b| b.0),
        gravity: a.gravity,
        softening: a.softening,
    };
    cases::scene::UserScene::resolve(source, file, &opts, a.end_time.unwrap_or(f64::INFINITY))
}

/// The time steps of a run that does not name them: the case's (block
/// steps), or global where a scene of the user's own stops after
/// `--steps` alone (block steps need an end time for their time line).
fn default_time_steps(a: &RunArgs, case: &dyn cases::Case, user_scene: bool) -> TimeSteps {
    if user_scene && a.end_time.is_none() {
        TimeSteps::Global
    } else {
        case.default_time_steps()
    }
}

/// Runs the case of the resolved options `a`.
fn execute(a: RunArgs) -> Result<(), AppError> {
    let user_scene = match (&a.case, &a.init, &a.restart) {
        (Some(name), _, _) => {
            refuse_scene_options(&a, name)?;
            None
        }
        (None, Some(spec), _) => Some(user_scene(
            &a,
            &format!("--init {spec} (no case)"),
            &crate::init::attributes(spec)?,
        )?),
        // A scene's checkpoint: its config.toml holds the whole physics.
        (None, None, Some(spec)) => {
            Some(user_scene(
            &a,
            &format!("--restart {spec} (a scene)"),
            &cases::scene::FileAttrs::default(),
        )?)
        }
        (None, None, None) => {
            return Err(AppError::Usage(format!(
                "no case given: name one ({}), give --init FILE for a scene of your own, or give --config FILE or --restart FILE",
                cases::names().join(", ")
            )))
        }
    };
    let case: &dyn cases::Case = match (&user_scene, &a.case) {
        (Some(s), _) => s,
        (None, Some(name)) => cases::lookup(name)?,
        (None, None) => unreachable!("a run without a case is a scene"),
    };
    let side = a.side.unwrap_or(case.default_side());
    if a.ng0 < 8 || a.ng0 > a.ngmax {
        return Err(AppError::Usage(format!(
            "--ng0 {} must be at least 8 and at most --ngmax {}",
            a.ng0, a.ngmax
        )));
    }
    // Output options are checked before any folder is made.
    outputs(&a, String::new(), f64::NEG_INFINITY)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(case.name()));
    // Before any work: a folder that cannot be made is a usage error.
    std::fs::create_dir_all(&out).map_err(|e| {
        AppError::Usage(format!(
            "--out {}: cannot create this folder ({e}); give a folder that can be created and written",
            out.display()
        ))
    })?;
    start_threads(a.threads)?;
    let kernel_choice = a.kernel;
    let kernel: FastKernel = kernel_choice.fast()?;

    let mut config = HydroConfig::default();
    config.curve = match a.curve {
        CurveArg::Hilbert => Curve::Hilbert,
        CurveArg::Morton => Curve::Morton,
    };
    // Kept only by cases with self-gravity.
    config.gravity = Some(sph_gravity::GravityParams {
        theta: a.theta,
        g: user_scene.as_ref().map_or(1.0, |s| s.g),
        ..Default::default()
    });
    // A scene's first step is the criteria's: it has no case to size one.
    if user_scene.is_some() && a.first_step.is_none() {
        config.timestep.first_step = sph_core::timestep::FirstStep::Criteria;
    }
    config.neighbors.ng0 = a.ng0;
    config.neighbors.ngmax = a.ngmax;
    config.bin_report = a.report_bins;
    config.time_steps = a
        .time_steps
        .unwrap_or_else(|| default_time_steps(&a, case, user_scene.is_some()));
    config.timestep.dt_max = a.dt_max;
    if let Some(on) = a.limiter {
        config.timestep.limiter = on;
    }
    if let Some(d) = a.limiter_factor {
        config.timestep.limiter_delta = d;
    }
    let stop = match (a.steps, a.end_time) {
        (Some(s), _) => Stop::Steps(s),
        (None, Some(t)) => Stop::Time(t),
        (None, None) if user_scene.is_some() => {
            return Err(AppError::Usage(
                "a scene of your own (--init FILE without a case) has no default end: give --end-time T or --steps N".into(),
            ))
        }
        (None, None) => Stop::Time(case.default_end_time()),
    };
    #[cfg(not(feature = "mpi"))]
    if let Some(n) = launched_ranks().filter(|&n| n > 1) {
        return Err(AppError::Usage(format!(
            "started as one of {n} MPI ranks, but this sphexa was built without MPI: every rank \
             would run the whole problem into the same files; build it with \
             `cargo build --release -p sph-apps --features mpi`, or run it without mpirun"
        )));
    }
    #[cfg(feature = "mpi")]
    let comm = sph_comm::MpiComm::init()?;
    #[cfg(not(feature = "mpi"))]
    let comm = sph_comm::SerialComm::new();
    let (rank, ranks) = (comm.rank(), comm.size());
    let root = rank == 0;
    // The case applies its own scheme with what the command line
    // overrides; each rank builds only its share of the particles.
    let share = cases::Share { rank, ranks };
    let overrides = scheme::scheme_overrides(&a)?;
    scheme::check_scheme(&overrides, case.default_scheme(), case.name())?;
    scheme::check_eos(&a, case)?;
    let layout = if a.lattice {
        cases::Layout::Lattice
    } else {
        cases::Layout::Glass {
            kernel: a.kernel,
            dir: crate::glass::default_cache_dir(),
        }
    };
    let mut scene = case.setup_share(side, config, &overrides, share, &layout)?;
    scene.config.validate()?;
    // A checkpoint, or a snapshot as initial conditions, replaces the
    // case's particles (each rank reads only its share).
    let loaded = match &a.restart {
        Some(spec) => Some(checkpoint::load(&comm, spec)?),
        None => None,
    };
    if let Some(l) = &loaded {
        if l.case.as_deref().is_some_and(|c| c != case.name()) {
            return Err(AppError::Usage(format!(
                "--restart {}: the checkpoint is of case '{}', not '{}'",
                l.path.display(),
                l.case.as_deref().unwrap_or(""),
                case.name()
            )));
        }
        scene.particles = checkpoint::particles(&l.rows, scene.config.fields(), &l.path)?;
        scene.total = l.total;
        scene.bbox = l.bbox;
    } else if let Some(spec) = &a.init {
        let (p, total, bbox) = crate::init::load(&comm, spec, scene.config.fields(), &scene.bbox)?;
        scene.particles = p;
        scene.total = total;
        // A scene keeps the box it resolved from the same file's
        // attributes and the options; a case takes the file's.
        if let (Some(b), None) = (bbox, &user_scene) {
            scene.bbox = b;
        }
    }
    let scene_keys = user_scene.as_ref().map(|s| resolved::SceneKeys {
        boundary: s.bbox.boundary(),
        cube: (a.cube.is_some() || s.bbox.boundary().contains(&sph_tree::Boundary::Periodic)).then(
            || {
                let (lo, hi) = (scene.bbox.lo(), scene.bbox.hi());
                [lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]]
            },
        ),
        g: scene.config.gravity.map(|g| g.g),
    });
    let resolved = resolved::resolved_config(
        &a,
        case.name(),
        side,
        stop,
        &out,
        &scene.config,
        scene_keys.as_ref(),
    );
    let config_text = toml::to_string(&resolved).expect("a TOML table serialises");
    if root {
        let path = out.join("config.toml");
        std::fs::write(&path, &config_text).map_err(|e| AppError::io(&path, e))?;
    }
    let outputs = outputs(
        &a,
        config_text,
        loaded.as_ref().map_or(f64::NEG_INFINITY, |l| l.state.t),
    )?;
    let gravity = scene.config.gravity.is_some();
    let block = scene.config.time_steps.on_time_line();
    let n = scene.total;
    if !a.quiet && root {
        eprintln!(
            "sphexa: {} with {n} particles, kernel {kernel_choice}, {ranks} rank(s) x {} threads, output in {}",
            case.name(),
            rayon::current_num_threads(),
            out.display()
        );
    }
    let progress = if a.quiet {
        Progress::Quiet
    } else {
        Progress::Auto
    };
    let sim = match &loaded {
        Some(l) => Simulation::resume(scene, kernel, kernel_choice.to_string(), comm, l.state)
            .and_then(|mut sim| sim.restore_stirring(l.stirring.as_ref()).map(|()| sim)),
        None => Simulation::with_comm(scene, kernel, kernel_choice.to_string(), comm),
    };
    let result = sim.and_then(|mut sim| {
        sim.set_write_particles(a.write_particles);
        if let Some(te) = a
            .end_time
            .or_else(|| user_scene.is_none().then(|| case.default_end_time()))
        {
            sim.set_time_line_end(te);
        }
        sim.set_rank_timings(a.rank_timings);
        sim.set_after_step(Some(crate::memory::return_free_heap_to_os));
        // Left at its default, the momentum bound is the run's: the tree's
        // accuracy with self-gravity, the time-stepping error under block
        // steps.
        let momentum = if a.max_momentum_drift == DEFAULT_MOMENTUM_BOUND {
            Bounds::for_run(gravity, block).momentum
        } else {
            a.max_momentum_drift
        };
        sim.set_watch(Some(Watch::new(
            Bounds {
                energy: a.max_energy_drift,
                momentum,
            },
            a.strict,
        )));
        sim.set_outputs(outputs)?;
        sim.run(stop, &out, progress)
    });
    let s = match result {
        Ok(s) => s,
        Err(e) if ranks > 1 => {
            // The other ranks may wait in a collective: leave without
            // finalising MPI, so that mpirun ends the job with this message.
            eprintln!("error on rank {rank} of {ranks}: {e}");
            std::process::exit(1);
        }
        Err(e) => return Err(e),
    };
    if !root {
        return Ok(());
    }
    say!(
        "{}: {} particles, {} steps to t = {:.4}, {:.1} s wall, {:.3e} particle-steps/s, peak RSS {:.0} MB",
        s.case,
        s.particles,
        s.steps,
        s.t_end,
        s.wall_s,
        s.particle_steps_per_s,
        s.peak_rss_bytes as f64 / 1e6
    );
    if let Some(l1) = s.l1 {
        say!("L1: rho {:.4e}  p {:.4e}  |v| {:.4e}", l1.rho, l1.p, l1.v);
    }
    if let (Some(r), Some(rr)) = (s.shock_radius, s.shock_radius_ref) {
        say!(
            "shock radius {r:.4} (reference {rr:.4}), peak density {:.3}",
            s.peak_density
        );
    }
    say!(
        "energy drift {:.3e}, momentum drift {:.3e}, angular momentum drift {:.3e}",
        s.energy_rel_drift,
        s.momentum_rel_drift,
        s.angular_momentum_rel_drift
    );
    if ranks > 1 {
        let d = s.domain;
        say!(
            "domain: {ranks} ranks, {}..{} particles per rank, halo ratio {:.3} (max {:.3}), {:.3e} bytes sent/step, sync {:.3e} s/step, communication {:.3e} s/step",
            d.owned_min, d.owned_max, d.halo_ratio_mean, d.halo_ratio_max,
            d.bytes_sent_per_step, d.sync_seconds_per_step, d.comm_seconds_per_step
        );
    }
    Ok(())
}
