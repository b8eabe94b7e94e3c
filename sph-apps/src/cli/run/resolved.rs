//! The resolved configuration of a run (`OUT/config.toml`, and the
//! `config` attribute of its snapshots and checkpoints): every option with
//! the value it ran with.

use super::args::{CurveArg, FormatArg, RunArgs, DEFAULT_MOMENTUM_BOUND};
use super::scheme::toml_value;
use crate::cases::scene::SceneGravity;
use crate::cases::SCHEME_OPTIONS;
use crate::cli::parse::{BoundaryArg, BoxArg};
use crate::simulation::Stop;
use sph_core::{Choice, HydroConfig};
use std::path::Path;

/// What a scene of the user's own resolved (`--init FILE` without a case):
/// its config.toml keeps it, so that `--config` and `--restart` repeat the
/// physics without reading the file's attributes again.
pub(crate) struct SceneKeys {
    /// The boundary of each axis.
    pub(crate) boundary: [sph_tree::Boundary; 3],
    /// The box, where it is needed (periodic axes) or was given.
    pub(crate) cube: Option<[f64; 6]>,
    /// The gravitational constant with self-gravity, or none.
    pub(crate) g: Option<f64>,
}

/// The fully resolved configuration of a run: every option with the value
/// it ran with (scheme options as the case and the overrides made them), so
/// `sphexa run --config OUT/config.toml` repeats the run.
pub(crate) fn resolved_config(
    a: &RunArgs,
    case: &str,
    side: usize,
    stop: Stop,
    out: &Path,
    config: &HydroConfig,
    scene: Option<&SceneKeys>,
) -> toml::Table {
    use toml::Value;
    let mut t = toml::Table::new();
    let mut set = |k: &str, v: Value| {
        t.insert(k.to_owned(), v);
    };
    match scene {
        // No case: `--init` (or the checkpoint) and the physics below.
        Some(k) => {
            set(
                "boundary",
                Value::String(BoundaryArg(k.boundary).to_string()),
            );
            if let Some(b) = k.cube {
                set("box", Value::String(BoxArg(b).to_string()));
            }
            let gravity = k.g.map_or(SceneGravity::Off, SceneGravity::Constant);
            set("gravity", Value::String(gravity.to_string()));
        }
        None => {
            set("case", Value::String(case.into()));
            set("side", Value::Integer(side as i64));
        }
    }
    match stop {
        Stop::Steps(n) => set("steps", Value::Integer(n as i64)),
        Stop::Time(te) => set("end-time", Value::Float(te)),
    }
    set("out", Value::String(out.display().to_string()));
    if let Some(n) = a.threads {
        set("threads", Value::Integer(n as i64));
    }
    set("kernel", Value::String(a.kernel.to_string()));
    if a.lattice {
        set("lattice", Value::Boolean(true));
    }
    set("ng0", Value::Integer(a.ng0 as i64));
    set("ngmax", Value::Integer(a.ngmax as i64));
    if let Some(s) = &a.scheme {
        set("scheme", Value::String(s.clone()));
    }
    let s = &config.scheme;
    set(
        "curve",
        Value::String(match a.curve {
            CurveArg::Hilbert => "hilbert".into(),
            CurveArg::Morton => "morton".into(),
        }),
    );
    set("courant", Value::Float(config.timestep.k_courant));
    set("eos", Value::String(config.eos.to_string()));
    // Runs that stir, or were told not to: others keep their config.toml.
    match config.stirring {
        Some(s) => set("stir", Value::String(s.to_string())),
        None if a.stir.is_some() => set("stir", Value::String("off".into())),
        None => {}
    }
    set(
        "first-step",
        Value::String(config.timestep.first_step.name().into()),
    );
    // Always: a checkpoint's configuration without the key is from a run
    // before block steps were the default, a global one.
    set("time-steps", Value::String(config.time_steps.name().into()));
    // Block-step runs only: others keep their config.toml.
    if config.time_steps.on_time_line() {
        if let Some(d) = config.timestep.dt_max {
            set("dt-max", Value::Float(d));
        }
        set(
            "limiter",
            Value::String(if config.timestep.limiter { "on" } else { "off" }.into()),
        );
        set(
            "limiter-factor",
            Value::Integer(config.timestep.limiter_factor().into()),
        );
    }
    for o in SCHEME_OPTIONS {
        set(o.key, toml_value((o.get)(s)));
    }
    set("theta", Value::Float(a.theta));
    if let Some(g) = config.gravity {
        set("softening", Value::Float(g.softening));
    }
    set("write-particles", Value::Boolean(a.write_particles));
    set("quiet", Value::Boolean(a.quiet));
    // The watch's options only when set: plain runs keep their config.toml.
    if a.strict {
        set("strict", Value::Boolean(true));
    }
    if a.report_bins {
        set("report-bins", Value::Boolean(true));
    }
    if a.rank_timings {
        set("rank-timings", Value::Boolean(true));
    }
    if a.max_energy_drift != 1e-2 {
        set("max-energy-drift", Value::Float(a.max_energy_drift));
    }
    if a.max_momentum_drift != DEFAULT_MOMENTUM_BOUND {
        set("max-momentum-drift", Value::Float(a.max_momentum_drift));
    }
    if let Some(f) = &a.snapshot_fields {
        set("snapshot-fields", Value::String(f.0.join(",")));
    }
    if a.snapshot_format == FormatArg::Swift {
        set("snapshot-format", Value::String("swift".into()));
    }
    if let Some(n) = a.snapshot_every_steps {
        set("snapshot-every-steps", Value::Integer(n as i64));
    }
    if let Some(x) = a.spectra_every_time {
        set("spectra-every-time", Value::Float(x));
    }
    if let Some(x) = a.snapshot_every_time {
        set("snapshot-every-time", Value::Float(x));
    }
    if let Some(at) = &a.snapshot_at {
        set(
            "snapshot-at",
            Value::Array(at.0.iter().map(|&x| Value::Float(x)).collect()),
        );
    }
    if let Some(c) = a.checkpoint_every {
        set("checkpoint-every", Value::String(c.to_string()));
    }
    if let Some(m) = a.mtbf {
        set("mtbf", Value::String(format!("{m}s")));
    }
    set("checkpoint-keep", Value::Integer(a.checkpoint_keep as i64));
    if let Some(r) = &a.restart {
        set("restart", Value::String(r.clone()));
    }
    if let Some(i) = &a.init {
        set("init", Value::String(i.clone()));
    }
    t
}
