//! Snapshot and checkpoint files of a run: what is asked for
//! ([`Outputs`], [`CheckpointEvery`]), their schedules, and the observer
//! that writes the files due after each step ([`FileOutputs`]).

use super::observer::{Observed, StepObserver, StepView};
use super::snapshot::{self as snapfile, Schedule};
use crate::{checkpoint, AppError};
use serde::Serialize;
use sph_comm::{Communicator, ReduceOp};
use sph_io::{Attr, FieldData, Snapshot};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The snapshot and checkpoint files of a run.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct IoSummary {
    /// Snapshot files written.
    pub snapshots: u64,
    /// Mean seconds per snapshot file (the slowest rank's).
    pub snapshot_seconds_mean: f64,
    /// Checkpoint files written.
    pub checkpoints: u64,
    /// Mean seconds per checkpoint file (the slowest rank's).
    pub checkpoint_seconds_mean: f64,
    /// With `--checkpoint-every auto`: the last interval chosen,
    /// sqrt(2 C M) seconds of wall-clock time.
    pub checkpoint_interval_s: Option<f64>,
}

/// When checkpoints are written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CheckpointEvery {
    /// After every step whose number is a multiple of this.
    Steps(u64),
    /// After the first step reaching each multiple of this simulated time.
    Time(f64),
    /// When this many wall-clock seconds have passed since the last one
    /// (the ranks agree through one max-reduction per step, the only
    /// collective the schedules add; `Auto` likewise).
    Wall(f64),
    /// Young/Daly: every sqrt(2 C M) seconds of wall-clock time, with C the
    /// measured time of the last checkpoint (the first is written after
    /// step 1 to measure it) and M the mean time between failures, seconds.
    Auto {
        /// Mean time between failures, seconds.
        mtbf_s: f64,
    },
}

/// Snapshot and checkpoint outputs of a run (none by default).
#[derive(Debug, Clone, Default)]
pub struct Outputs {
    /// Snapshot fields (`x`, `rho`, ...; see
    /// [`crate::output::snapshot::base_fields`]) and schedule.
    pub snapshots: Option<(Vec<String>, Schedule)>,
    /// Checkpoint schedule and how many of this run's checkpoints to keep
    /// (older ones are deleted once a newer one is complete; 0 keeps all).
    pub checkpoints: Option<(CheckpointEvery, usize)>,
    /// Attributes of every snapshot and checkpoint (the run's settings).
    pub attrs: Vec<(String, Attr)>,
    /// The layout of the snapshots (checkpoints are always ours).
    pub format: SnapshotFormat,
    /// Velocity spectra and ln-rho PDFs after the first step reaching
    /// each multiple of this time ([`crate::output::spectra`]).
    pub spectra_every_time: Option<f64>,
}

/// The layout snapshots are written in.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum SnapshotFormat {
    /// Ours: H5Part, the fields asked for, with checksums.
    #[default]
    H5Part,
    /// SWIFT's snapshot layout (`sph_io::swift`): the gas's coordinates in
    /// `[0, BoxSize)`, velocities, masses, smoothing lengths in SWIFT's
    /// convention (ours times `h_per_h`, [`sph_io::swift::swift_h_per_h`]
    /// of the run's kernel), internal energies, ids, densities and
    /// pressures. The particles are gathered to every rank and rank 0
    /// writes the file.
    Swift {
        /// SWIFT's `h` per ours for the run's kernel.
        h_per_h: f64,
    },
}

/// The file outputs of a run in progress: schedules, folders, what was
/// written.
#[derive(Debug)]
pub struct FileOutputs {
    /// Attributes of every file: the run's settings and its case.
    attrs: Vec<(String, Attr)>,
    snapshots: Option<(Vec<String>, Schedule)>,
    format: SnapshotFormat,
    snapshot_dir: PathBuf,
    checkpoint_every: Option<CheckpointEvery>,
    checkpoint_schedule: Schedule,
    checkpoint_dir: PathBuf,
    keep: usize,
    written: Vec<PathBuf>,
    checkpoint_cost: Option<f64>,
    last_checkpoint: Instant,
    /// What was written so far.
    pub summary: IoSummary,
    /// The test hook of [`checkpoint`], if set.
    pause: Option<checkpoint::TestPause>,
    /// A checkpoint fell due and waits for a synchronisation point.
    checkpoint_latched: bool,
    /// The scheme keeps h fixed: a snapshot between sub-steps leaves h.
    fixed_h: bool,
}

impl FileOutputs {
    /// The files `o` asks for of a run of `case` writing into `out`, with
    /// time schedules counted from `t0` (a resumed run's start time, else
    /// -inf); `fixed_h`: the scheme keeps smoothing lengths fixed.
    ///
    /// # Errors
    /// A bad test hook ([`checkpoint::TestPause::from_env`]).
    pub fn new(
        o: &Outputs,
        case: &str,
        out: &Path,
        t0: f64,
        fixed_h: bool,
    ) -> Result<Self, AppError> {
        let (every, keep) = match o.checkpoints {
            Some((e, k)) => (Some(e), k),
            None => (None, 0),
        };
        let checkpoint_schedule = match every {
            Some(CheckpointEvery::Steps(n)) => Schedule::new(Some(n), None, Vec::new(), t0),
            Some(CheckpointEvery::Time(dt)) => Schedule::new(None, Some(dt), Vec::new(), t0),
            _ => Schedule::default(),
        };
        let snapshots = o.snapshots.clone().map(|(f, s)| {
            let s = Schedule::new(s.every_steps, s.every_time, s.at.clone(), t0);
            (f, s)
        });
        let pause = match every {
            Some(_) => checkpoint::TestPause::from_env()?,
            None => None,
        };
        let mut attrs = o.attrs.clone();
        attrs.push(("case".into(), Attr::Str(case.into())));
        Ok(FileOutputs {
            attrs,
            snapshots,
            format: o.format,
            snapshot_dir: out.join("snapshots"),
            checkpoint_every: every,
            checkpoint_schedule,
            checkpoint_dir: out.join("checkpoints"),
            keep,
            written: Vec::new(),
            checkpoint_cost: None,
            last_checkpoint: Instant::now(),
            summary: IoSummary::default(),
            pause,
            checkpoint_latched: false,
            fixed_h,
        })
    }

    /// Whether any file is asked for.
    pub fn any(&self) -> bool {
        self.snapshots.is_some() || self.checkpoint_every.is_some()
    }

    /// Creates the folders of the files (rank 0).
    ///
    /// # Errors
    /// A folder that cannot be created.
    pub fn create_dirs(&self) -> Result<(), AppError> {
        for dir in [self.snapshot_dir.as_path(), self.checkpoint_dir.as_path()] {
            std::fs::create_dir_all(dir).map_err(|e| AppError::io(dir, e))?;
        }
        Ok(())
    }
}

impl<C: Communicator> StepObserver<C> for FileOutputs {
    /// The snapshot and checkpoint due after the step just taken (before
    /// anything else touches the particles). Collective.
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        if !self.any() {
            return Ok(Observed::Recorded);
        }
        let files = self;
        let state = view.state;
        let (step, t) = (state.step, state.t);
        let owned = view.owned.clone();
        let p = view.particles;
        let comm = view.comm;
        let attrs = &files.attrs;
        let time_due = files.snapshots.as_ref().and_then(|(_, s)| s.time_due(t));
        let snapshot_due = files
            .snapshots
            .as_mut()
            .is_some_and(|(_, s)| s.due(step, t));
        if snapshot_due {
            // Block time steps: a snapshot asked for at a time holds the
            // state at that time, predicted back within the sub-step just
            // taken; a global run writes the state after the step.
            let at = view.output_time(time_due);
            let t_snap = at.map_or(t, |(_, t_out)| t_out);
            let fixed_h = files.fixed_h;
            let field = |name: &str| -> Result<FieldData, AppError> {
                let mut data =
                    snapfile::field(p, owned.clone(), name).expect("checked by set_outputs");
                if let FieldData::F64(v) = &mut data {
                    if !(name == "h" && fixed_h) {
                        view.predict_owned(name, v, at)?;
                    }
                }
                Ok(data)
            };
            let seconds = match files.format {
                SnapshotFormat::Swift { h_per_h } => {
                    let path = snapfile::numbered(&files.snapshot_dir, "snapshot", step)
                        .with_extension("hdf5");
                    write_swift_snapshot(view, &path, h_per_h, t_snap, &field)?
                }
                SnapshotFormat::H5Part => {
                    let fields = &files.snapshots.as_ref().expect("snapshots on").0;
                    let mut snap =
                        Snapshot::new(step, t_snap, state.dt_prev, snapfile::box_spec(view.bbox));
                    for (name, value) in attrs {
                        snap.set_attr(name, value.clone());
                    }
                    snap.set_attr("sphexa_kind", Attr::Str("snapshot".into()));
                    for name in fields {
                        snap.set_field(name, field(name)?);
                    }
                    let path = snapfile::numbered(&files.snapshot_dir, "snapshot", step);
                    snapfile::write(comm, &path, &snap)?
                }
            };
            let io = &mut files.summary;
            io.snapshot_seconds_mean = (io.snapshot_seconds_mean * io.snapshots as f64 + seconds)
                / (io.snapshots + 1) as f64;
            io.snapshots += 1;
        }
        let checkpoint_due = match files.checkpoint_every {
            None => false,
            Some(CheckpointEvery::Steps(_) | CheckpointEvery::Time(_)) => {
                files.checkpoint_schedule.due(step, t)
            }
            Some(CheckpointEvery::Wall(interval)) => {
                let late = files.last_checkpoint.elapsed().as_secs_f64() >= interval;
                comm.all_reduce_scalar(u64::from(late), ReduceOp::Max) > 0
            }
            Some(CheckpointEvery::Auto { mtbf_s }) => {
                let late = match files.checkpoint_cost {
                    None => true,
                    Some(c) => {
                        let interval = (2.0 * c * mtbf_s).sqrt();
                        files.summary.checkpoint_interval_s = Some(interval);
                        files.last_checkpoint.elapsed().as_secs_f64() >= interval
                    }
                };
                comm.all_reduce_scalar(u64::from(late), ReduceOp::Max) > 0
            }
        };
        // Block time steps: a due checkpoint waits for the next
        // synchronisation point (every particle's step ended), where a
        // restart continues the hierarchy to the bit.
        files.checkpoint_latched |= checkpoint_due;
        let checkpoint_due = files.checkpoint_latched && view.report.ends_synchronised;
        if checkpoint_due {
            files.checkpoint_latched = false;
            let mut snap = checkpoint::snapshot(p, owned, state, view.bbox, attrs);
            if let Some(s) = view.stirring {
                for (name, value) in checkpoint::StirState::attrs(s, state.external_work) {
                    snap.set_attr(&name, value);
                }
            }
            let path = snapfile::numbered(&files.checkpoint_dir, "checkpoint", step);
            let nth = files.summary.checkpoints + 1;
            let pause = files.pause.as_ref();
            let seconds = snapfile::write_then_commit(comm, &path, &snap, || {
                pause.map_or(Ok(()), |p| p.pause_if_due(nth, &path))
            })?;
            files.checkpoint_cost = Some(seconds);
            files.last_checkpoint = Instant::now();
            let io = &mut files.summary;
            io.checkpoint_seconds_mean = (io.checkpoint_seconds_mean * io.checkpoints as f64
                + seconds)
                / (io.checkpoints + 1) as f64;
            io.checkpoints += 1;
            files.written.push(path);
            if files.keep > 0 && files.written.len() > files.keep && comm.rank() == 0 {
                let old = files.written.remove(0);
                std::fs::remove_file(&old).map_err(|e| AppError::io(&old, e))?;
            }
        }
        Ok(if checkpoint_due {
            Observed::Checkpoint
        } else {
            Observed::Recorded
        })
    }
}

/// Writes the particles of `view` as a SWIFT snapshot at `path` (rank 0,
/// after gathering every rank's). Collective; returns the longest time a
/// rank spent, in seconds.
fn write_swift_snapshot<C: Communicator>(
    view: &StepView<'_, C>,
    path: &Path,
    h_per_h: f64,
    time: f64,
    field: &dyn Fn(&str) -> Result<FieldData, AppError>,
) -> Result<f64, AppError> {
    use sph_io::swift::{write_swift, SwiftParticles};
    let start = Instant::now();
    let (comm, p, owned) = (view.comm, view.particles, view.owned.clone());
    // Every rank's owned values of a field, in rank order.
    let gather = |name: &str| -> Result<Vec<f64>, AppError> {
        let FieldData::F64(mine) = field(name)? else {
            unreachable!("{name} is an f64 field")
        };
        let got = comm.all_gather_v(&mine)?;
        Ok((0..comm.size())
            .flat_map(|r| got.from_rank(r).to_vec())
            .collect())
    };
    let ids = comm.all_gather_v(&p.id[owned.clone()])?;
    let (lo, hi) = (view.bbox.lo(), view.bbox.hi());
    let mut gas = SwiftParticles {
        x: gather("x")?,
        y: gather("y")?,
        z: gather("z")?,
        vx: gather("vx")?,
        vy: gather("vy")?,
        vz: gather("vz")?,
        m: gather("m")?,
        h: gather("h")?,
        u: gather("u")?,
        id: (0..comm.size())
            .flat_map(|r| ids.from_rank(r).to_vec())
            .collect(),
        rho: Some(gather("rho")?),
        p: Some(gather("p")?),
        box_size: std::array::from_fn(|k| hi[k] - lo[k]),
        time,
        units: None,
    };
    gas.shift(lo.map(|l| -l));
    gas.scale_h(h_per_h);
    let written = if comm.rank() == 0 {
        write_swift(path, &gas).map_err(snapfile::io_error)
    } else {
        Ok(())
    };
    let failed = comm.all_reduce_scalar(u64::from(written.is_err()), ReduceOp::Max);
    written?;
    if failed > 0 {
        return Err(AppError::Usage(format!(
            "{}: rank 0 failed to write the snapshot (see its message)",
            path.display()
        )));
    }
    Ok(comm.all_reduce_scalar(start.elapsed().as_secs_f64(), ReduceOp::Max))
}
