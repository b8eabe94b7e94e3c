//! Checkpoints: every persistent field of every particle and the run state
//! of the integrator, so that a run continues from one to the bit
//! (`sphexa run --restart FILE[:STEP]`).
//!
//! A checkpoint is a snapshot file ([`crate::output::snapshot`]: H5Part,
//! one step group, every rank writing its rows) with
//!
//! - the fields the next step reads before it writes them: `id`, `x`, `y`,
//!   `z`, `vx`, `vy`, `vz`, `h`, `m`, `u`, the integrator's history `dx`,
//!   `dy`, `dz` (last position change) and `du_prev` (last du/dt), and,
//!   where the run has them, `alpha` (AV switches) and `rho0`, `p0` (the
//!   per-particle reference state of a referenced equation of state).
//!   Density, pressure, the IAD matrices, Omega, accelerations and the
//!   gravitational potential are recomputed by every step and not stored.
//! - attributes: `iteration` (steps done), `time`, `minDt` (the last step,
//!   the integrator's `dt_{n-1}`), the box, `h_next_max` (the largest h
//!   after the last update, which the next step's halos use; NaN before the
//!   first step), `sphexa_kind` = `checkpoint`, `case`, and `config`: the
//!   run's resolved configuration as TOML (what `--restart` runs with);
//!   a stirred run adds [`EXTERNAL_WORK`], [`STIR_PHASES`] and
//!   [`STIR_RNG`] ([`StirState`]).
//!
//! Everything is stored in full `f64`/`u64` precision, so nothing is lost.
//!
//! # Test hook
//! [`PAUSE_VAR`] (`SPHEXA_TEST_PAUSE_IN_CHECKPOINT=K:DIR`) makes a run stop
//! inside its K-th checkpoint write, with the data in `NAME.tmp` and before
//! the rename, after creating the file [`PAUSE_MARKER`] in `DIR`: a test
//! waits for the marker and kills the process there, certain that the kill
//! lands during a write. It is read once per run when checkpoints are on;
//! unset (or empty) it does nothing.

use crate::output::snapshot::{self, field};
use crate::AppError;
use sph_comm::Communicator;
use sph_core::fields::Column;
use sph_core::{BlockRun, FieldSet, Particles, RunState};
use sph_io::{Attr, FieldData, H5Part, Selection, Snapshot, SnapshotReader};
use sph_tree::BoundingBox;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Value of attribute `sphexa_kind` in checkpoints.
pub const KIND: &str = "checkpoint";

/// The environment variable of the [test hook](self#test-hook).
pub const PAUSE_VAR: &str = "SPHEXA_TEST_PAUSE_IN_CHECKPOINT";

/// The file the [test hook](self#test-hook) creates when it pauses.
pub const PAUSE_MARKER: &str = "paused-in-checkpoint";

/// Where the [test hook](self#test-hook) pauses: in the `nth` checkpoint
/// write of the run (1 for the first), creating [`PAUSE_MARKER`] in `dir`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TestPause {
    /// The checkpoint to pause in, counted from 1.
    pub nth: u64,
    /// Folder of the marker file.
    pub dir: PathBuf,
}

impl TestPause {
    /// The pause [`PAUSE_VAR`] asks for; `None` when it is unset or empty.
    ///
    /// # Errors
    /// A value that is not `K:DIR`, named.
    pub fn from_env() -> Result<Option<Self>, AppError> {
        match std::env::var_os(PAUSE_VAR) {
            Some(v) if !v.is_empty() => Self::parse(&v.to_string_lossy()).map(Some),
            _ => Ok(None),
        }
    }

    /// Parses `K:DIR` (K >= 1; DIR may contain `:`).
    ///
    /// # Errors
    /// Another form, named with the one allowed.
    pub fn parse(value: &str) -> Result<Self, AppError> {
        let bad = || {
            AppError::Usage(format!(
                "{PAUSE_VAR}='{value}': expected K:DIR (pause in the K-th checkpoint write, K >= 1, \
                 creating DIR/{PAUSE_MARKER}); it is a test hook, unset it for real runs"
            ))
        };
        let (k, dir) = value.split_once(':').ok_or_else(bad)?;
        let nth = k.parse::<u64>().ok().filter(|&k| k >= 1).ok_or_else(bad)?;
        if dir.is_empty() {
            return Err(bad());
        }
        Ok(TestPause {
            nth,
            dir: PathBuf::from(dir),
        })
    }

    /// In checkpoint write `nth` (of file `path`): creates the marker,
    /// naming `path`, and blocks this thread for good (the test kills the
    /// process). Other writes return at once.
    ///
    /// # Errors
    /// The marker cannot be written (the write then fails, so a broken
    /// test set-up does not wait forever).
    pub fn pause_if_due(&self, nth: u64, path: &Path) -> Result<(), AppError> {
        if nth != self.nth {
            return Ok(());
        }
        let marker = self.dir.join(PAUSE_MARKER);
        // Written under another name and renamed: the test never sees a
        // marker half written.
        let part = self.dir.join(format!("{PAUSE_MARKER}.part"));
        std::fs::write(&part, path.display().to_string())
            .and_then(|()| std::fs::rename(&part, &marker))
            .map_err(|e| AppError::io(&marker, e))?;
        loop {
            std::thread::park();
        }
    }
}

/// The checkpoint fields of particles `p` (see the [module docs](self)):
/// from the field table, the id, the persistent state and the
/// integrator's history that `p` holds.
pub fn fields(p: &Particles) -> Vec<&'static str> {
    sph_core::fields::checkpointed(p.fields())
        .map(|f| f.name)
        .collect()
}

/// The checkpoint of this rank's particles `owned` of `p` with the run
/// state `s` and box `bbox`, carrying `attrs` (run settings) too.
pub fn snapshot(
    p: &Particles,
    owned: Range<usize>,
    s: RunState,
    bbox: &BoundingBox,
    attrs: &[(String, Attr)],
) -> Snapshot {
    let mut snap = Snapshot::new(s.step, s.t, s.dt_prev, snapshot::box_spec(bbox));
    for (name, value) in attrs {
        snap.set_attr(name, value.clone());
    }
    snap.set_attr("sphexa_kind", Attr::Str(KIND.into()))
        .set_attr("h_next_max", Attr::F64(s.h_next_max.unwrap_or(f64::NAN)));
    if let Some(b) = s.block {
        snap.set_attr(TIME_LINE, Attr::F64Array(vec![b.t_begin, b.t_end]))
            .set_attr(TIME_LINE_TOP_BIN, Attr::I64(i64::from(b.dt_max_bin)))
            .set_attr(TIME_LINE_DT_MAX, Attr::F64(b.dt_max))
            .set_attr(TIME_LINE_TICK, Attr::I64(b.ti as i64))
            .set_attr(PARTICLE_UPDATES, Attr::I64(b.updates as i64))
            .set_attr(DOMAIN_SYNCS, Attr::I64(b.syncs as i64));
        if b.ramp_origin.is_finite() {
            snap.set_attr(TIME_LINE_RAMP_ORIGIN, Attr::F64(b.ramp_origin));
        }
    }
    for name in fields(p) {
        if let Some(data) = field(p, owned.clone(), name) {
            snap.set_field(name, data);
        }
    }
    snap
}

/// Attribute of block-step runs: the time line's start and end times.
pub const TIME_LINE: &str = "time_line";
/// Attribute of block-step runs: the longest step any particle may take.
pub const TIME_LINE_DT_MAX: &str = "time_line_dt_max";
/// Attribute of block-step runs with a start ramp: its origin (absent:
/// no ramp).
pub const TIME_LINE_RAMP_ORIGIN: &str = "time_line_ramp_origin";
/// Attribute of block-step runs: the longest step's bin.
pub const TIME_LINE_TOP_BIN: &str = "time_line_top_bin";
/// Attribute of block-step runs: the tick of the checkpoint (a
/// synchronisation point).
pub const TIME_LINE_TICK: &str = "time_line_tick";
/// Attribute of block-step runs: particle updates so far.
pub const PARTICLE_UPDATES: &str = "particle_updates";
/// Attribute of block-step runs: domain syncs so far.
pub const DOMAIN_SYNCS: &str = "domain_syncs";

/// Attribute: the stirring's work up to the checkpoint's time (stirred
/// runs only; 0 when absent).
pub const EXTERNAL_WORK: &str = "external_work";
/// Attribute: the stirring's OU phases (stirred runs only).
pub const STIR_PHASES: &str = "stir_phases";
/// Attribute: the stirring's random-number generator state, 625 exact
/// integers (stirred runs only).
pub const STIR_RNG: &str = "stir_rng";

/// The driving state of a stirred run, as a checkpoint holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct StirState {
    /// OU phases ([`sph_core::stirring::Stirring::phases`]).
    pub phases: Vec<f64>,
    /// Generator state ([`sph_core::stirring::Stirring::rng_state`]).
    pub rng: Vec<f64>,
}

impl StirState {
    /// The attributes a checkpoint of a stirred run carries: the work
    /// done so far (`work`) and the driving state of `s`.
    pub fn attrs(s: &sph_core::stirring::Stirring, work: f64) -> Vec<(String, Attr)> {
        vec![
            (EXTERNAL_WORK.into(), Attr::F64(work)),
            (STIR_PHASES.into(), Attr::F64Array(s.phases().to_vec())),
            (STIR_RNG.into(), Attr::F64Array(s.rng_state())),
        ]
    }
}

/// A checkpoint as read by one rank: its share of the particles and what
/// the whole run continues from.
#[derive(Debug)]
pub struct Loaded {
    /// The file.
    pub path: PathBuf,
    /// Run state of the integrator.
    pub state: RunState,
    /// Simulation box.
    pub bbox: BoundingBox,
    /// Particles of all ranks.
    pub total: usize,
    /// This rank's rows (every checkpoint field).
    pub rows: Snapshot,
    /// The run's resolved configuration (TOML), if stored.
    pub config: Option<String>,
    /// The case, if stored.
    pub case: Option<String>,
    /// The driving state of a stirred run.
    pub stirring: Option<StirState>,
}

/// Splits `FILE[:STEP]` into the file and the step, if given (`FILE` is
/// taken whole when it exists as it is or its suffix is not a number).
pub fn split_spec(spec: &str) -> Result<(PathBuf, Option<u64>), AppError> {
    if Path::new(spec).exists() {
        return Ok((PathBuf::from(spec), None));
    }
    match spec.rsplit_once(':') {
        Some((file, step)) if !file.is_empty() && step.chars().all(|c| c.is_ascii_digit()) => {
            let step = step.parse::<u64>().map_err(|_| {
                AppError::Usage(format!("'{spec}': step '{step}' is not a whole number"))
            })?;
            Ok((PathBuf::from(file), Some(step)))
        }
        _ => Ok((PathBuf::from(spec), None)),
    }
}

/// Index of the step group of `path` whose `iteration` is `step` (the last
/// group when `step` is `None`).
pub fn group_of_step(path: &Path, step: Option<u64>) -> Result<usize, AppError> {
    let count = H5Part.step_count(path).map_err(snapshot::io_error)?;
    if count == 0 {
        return Err(AppError::Usage(format!(
            "{}: the file holds no step group",
            path.display()
        )));
    }
    let Some(step) = step else {
        return Ok(count - 1);
    };
    let mut found = Vec::with_capacity(count);
    for k in 0..count {
        let meta = H5Part
            .read_step(path, k, &Selection::Names(Vec::new()))
            .map_err(snapshot::io_error)?;
        if meta.step == step {
            return Ok(k);
        }
        found.push(meta.step.to_string());
    }
    Err(AppError::Usage(format!(
        "{}: no step {step}; the file holds step(s) {}",
        path.display(),
        found.join(", ")
    )))
}

/// Reads this rank's share of the checkpoint `spec` (`FILE[:STEP]`).
/// Collective.
///
/// # Errors
/// A missing or corrupted file, a file that is not a checkpoint, a missing
/// field, named.
pub fn load<C: Communicator>(comm: &C, spec: &str) -> Result<Loaded, AppError> {
    let (path, step) = split_spec(spec)?;
    let index = group_of_step(&path, step)?;
    let (rows, total) = snapshot::read_share(comm, &path, index, &Selection::All)?;
    let text = |name: &str| match rows.attr(name) {
        Some(Attr::Str(s)) => Some(s.clone()),
        _ => None,
    };
    if text("sphexa_kind").as_deref() != Some(KIND) {
        return Err(AppError::Usage(format!(
            "{}: not a checkpoint (attribute sphexa_kind is not '{KIND}'); a snapshot can start a case with --init",
            path.display()
        )));
    }
    // The file's checksums hold; these are values no run writes.
    let bad = |what: String| {
        AppError::Usage(format!(
            "{}: {what}; not a checkpoint a run can continue from",
            path.display()
        ))
    };
    if !rows.time.is_finite() {
        return Err(bad(format!("its time is {}", rows.time)));
    }
    if !(rows.dt.is_finite() && rows.dt > 0.0) {
        return Err(bad(format!(
            "its last time step (minDt) is {}, not a positive number",
            rows.dt
        )));
    }
    let h_next_max = match rows.attr("h_next_max") {
        Some(Attr::F64(h)) if h.is_finite() && *h <= 0.0 => {
            return Err(bad(format!("h_next_max is {h}, not positive")))
        }
        Some(Attr::F64(h)) if h.is_finite() => Some(*h),
        _ => None,
    };
    let external_work = match rows.attr(EXTERNAL_WORK) {
        Some(Attr::F64(w)) if w.is_finite() => *w,
        Some(other) => {
            return Err(bad(format!(
                "{EXTERNAL_WORK} is {other:?}, not a finite number"
            )))
        }
        None => 0.0,
    };
    let stirring = match (rows.attr(STIR_PHASES), rows.attr(STIR_RNG)) {
        (Some(Attr::F64Array(phases)), Some(Attr::F64Array(rng))) => Some(StirState {
            phases: phases.clone(),
            rng: rng.clone(),
        }),
        (None, None) => None,
        _ => {
            return Err(bad(format!(
                "its stirring state is incomplete or mistyped ({STIR_PHASES} and {STIR_RNG} must both be f64 arrays)"
            )))
        }
    };
    let block = block_run(&rows).map_err(bad)?;
    let state = RunState {
        step: rows.step,
        t: rows.time,
        dt_prev: rows.dt,
        h_next_max,
        external_work,
        block,
    };
    let bbox = snapshot::bounding_box(&rows.bbox).map_err(|e| bad(format!("its box: {e}")))?;
    let total = usize::try_from(total)
        .map_err(|_| bad(format!("{total} particles do not fit in memory")))?;
    Ok(Loaded {
        path,
        state,
        bbox,
        total,
        config: text("config"),
        case: text("case"),
        stirring,
        rows,
    })
}

/// The time line of a block-step run's checkpoint (none without its
/// attributes); what is wrong, in words.
fn block_run(rows: &Snapshot) -> Result<Option<BlockRun>, String> {
    let count = |name: &str| match rows.attr(name) {
        Some(Attr::I64(v)) if *v >= 0 => Ok(*v as u64),
        other => Err(format!("{name} is {other:?}, not a whole number >= 0")),
    };
    match rows.attr(TIME_LINE) {
        None => Ok(None),
        Some(Attr::F64Array(span)) if span.len() == 2 => {
            let top = count(TIME_LINE_TOP_BIN)?;
            let top =
                u8::try_from(top).map_err(|_| format!("{TIME_LINE_TOP_BIN} {top} is too large"))?;
            let dt_max = match rows.attr(TIME_LINE_DT_MAX) {
                Some(Attr::F64(v)) if *v > 0.0 => *v,
                other => {
                    return Err(format!(
                        "{TIME_LINE_DT_MAX} is {other:?}, not a positive time"
                    ))
                }
            };
            let ramp_origin = match rows.attr(TIME_LINE_RAMP_ORIGIN) {
                None => f64::NEG_INFINITY,
                Some(Attr::F64(v)) if v.is_finite() => *v,
                other => return Err(format!("{TIME_LINE_RAMP_ORIGIN} is {other:?}, not a time")),
            };
            Ok(Some(BlockRun {
                t_begin: span[0],
                ramp_origin,
                t_end: span[1],
                dt_max_bin: top,
                dt_max,
                ti: count(TIME_LINE_TICK)?,
                updates: count(PARTICLE_UPDATES)?,
                syncs: count(DOMAIN_SYNCS)?,
            }))
        }
        Some(other) => Err(format!(
            "{TIME_LINE} is {other:?}, not the two times of a time line"
        )),
    }
}

/// Particles with the optional `fields` and, from `rows`, every value a
/// checkpoint of such a run stores (a referenced EOS's `rho0` and `p0`
/// where `rows` has them).
///
/// # Errors
/// A checkpoint field missing from `rows` or of the wrong type, named.
pub fn particles(rows: &Snapshot, fields: FieldSet, path: &Path) -> Result<Particles, AppError> {
    let n = rows.len();
    let mut fields = fields;
    fields.eos_ref |= rows.field("rho0").is_some();
    let mut p = Particles::new(n, fields);
    let missing = |name: &str| {
        AppError::Usage(format!(
            "{}: the checkpoint has no field '{name}' of the right type (it holds: {})",
            path.display(),
            rows.fields
                .iter()
                .map(|f| f.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    };
    // Every field as long as the first: the copies below need it.
    if let Some(f) = rows.fields.iter().find(|f| f.data.len() != n) {
        return Err(AppError::Usage(format!(
            "{}: field '{}' has {} values, field '{}' {n}",
            path.display(),
            f.name,
            f.data.len(),
            rows.fields[0].name
        )));
    }
    for f in sph_core::fields::checkpointed(fields) {
        match (f.column, rows.field(f.name)) {
            (Column::F64(_, get), Some(FieldData::F64(v))) => get(&mut p).copy_from_slice(v),
            (Column::U64(_, get), Some(FieldData::U64(v))) => get(&mut p).copy_from_slice(v),
            _ => return Err(missing(f.name)),
        }
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_test_hook_reads_k_and_a_folder_and_names_a_bad_value() {
        assert_eq!(
            TestPause::parse("4:/a/b:c").unwrap(),
            TestPause {
                nth: 4,
                dir: PathBuf::from("/a/b:c")
            }
        );
        for bad in ["4", "0:/a", "x:/a", "4:", ":/a"] {
            let e = TestPause::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains(PAUSE_VAR) && e.contains(&format!("'{bad}'")) && e.contains("K:DIR"),
                "{e}"
            );
        }
        // Not the checkpoint to pause in: returns at once, writes nothing.
        let dir = crate::test_dir("pause");
        let p = TestPause {
            nth: 2,
            dir: dir.clone(),
        };
        p.pause_if_due(1, Path::new("c.h5")).unwrap();
        p.pause_if_due(3, Path::new("c.h5")).unwrap();
        assert!(!dir.join(PAUSE_MARKER).exists());
    }
}
