//! Particle snapshots and checkpoints: HDF5 files in the H5Part layout
//! (`sph-io`), one file per output, written by every rank into one file
//! without gathering particles.
//!
//! # How the ranks write one file
//! `hdf5-pure` (the default, pure-Rust backend) has no parallel HDF5, so a
//! write is coordinated by rank 0 ([`sph_io::slab`]): every rank sends the
//! row count and per-field CRC32 of its own particles to all (a few words
//! per rank, one all-gather); rank 0 writes `NAME.tmp` with the metadata and
//! the datasets sized for all rows (their values still holes), and sends
//! the datasets' byte offsets to all; every rank writes its rows in place,
//! at the sum of the row counts of the ranks before it, and syncs; after a
//! reduction that also agrees on success, rank 0 renames `NAME.tmp` to
//! `NAME`. Ranks own contiguous ranges of the space-filling curve, so the
//! rows are in global curve order, as a serial run writes them: the file
//! does not depend on the rank count.
//!
//! # Reading with any rank count
//! [`read_share`]: rank `r` of `R` reads rows `total * r / R .. total *
//! (r + 1) / R`, the ranks combine their partial checksums and all check
//! them, so a file written by N ranks is read by any number of ranks.
//!
//! # Schedules
//! [`Schedule`]: every N steps, every T of simulated time, and at listed
//! times. Outputs never shorten a step: a snapshot due at time T is written
//! after the first step that reaches T, so the physics does not depend on
//! the output schedule.

use crate::AppError;
use sph_comm::{Communicator, ReduceOp};
use sph_core::fields::{Column, Field, Needs, FIELDS};
use sph_core::Particles;
use sph_io::slab::{self, SlabSummary};
use sph_io::{Attr, BoxSpec, FieldData, IoError, Selection, Snapshot};
use sph_tree::{Boundary, BoundingBox};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Fields every run has, in the order `--snapshot-fields` lists them
/// (from the field table, [`sph_core::fields::FIELDS`]).
pub fn base_fields() -> Vec<&'static str> {
    let always = |f: &&Field| f.needs == Needs::Always;
    FIELDS.iter().filter(always).map(|f| f.name).collect()
}

/// Fields only runs with the matching physics have: referenced equation
/// of state, AV switches, grad-h factor, self-gravity, IAD matrices.
pub fn optional_fields() -> Vec<&'static str> {
    let optional = |f: &&Field| f.needs != Needs::Always;
    FIELDS.iter().filter(optional).map(|f| f.name).collect()
}

/// The snapshot fields when `--snapshot-fields` is not given.
pub const DEFAULT_FIELDS: &[&str] = &[
    "x", "y", "z", "vx", "vy", "vz", "h", "m", "u", "rho", "p", "id",
];

/// The values of field `name` of the particles `owned` of `p`, or `None`
/// when the run does not have the field.
pub fn field(p: &Particles, owned: Range<usize>, name: &str) -> Option<FieldData> {
    let f = sph_core::fields::find(name).filter(|f| p.fields().holds(f.needs))?;
    Some(match f.column {
        Column::F64(get, _) => FieldData::F64(get(p)[owned].to_vec()),
        Column::U64(get, _) => FieldData::U64(get(p)[owned].to_vec()),
        Column::U32(get, _) => {
            FieldData::U64(get(p)[owned].iter().map(|&c| u64::from(c)).collect())
        }
    })
}

/// Parses a `--snapshot-fields` list (`x,y,z,rho`): known names, each
/// once, at least one.
///
/// # Errors
/// An unknown or repeated name, named with the fields there are.
pub fn parse_fields(list: &str) -> Result<Vec<String>, String> {
    let mut out: Vec<String> = Vec::new();
    for name in list.split(',').map(str::trim) {
        if sph_core::fields::find(name).is_none() {
            return Err(format!(
                "unknown field '{name}'; fields: {} (and, where the run has them, {})",
                base_fields().join(","),
                optional_fields().join(",")
            ));
        }
        if out.iter().any(|n| n == name) {
            return Err(format!("field '{name}' is listed twice"));
        }
        out.push(name.to_owned());
    }
    Ok(out)
}

/// When outputs are written. All parts may be combined; an output is
/// written once per step however many parts are due.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Schedule {
    /// After every step whose number is a multiple of this.
    pub every_steps: Option<u64>,
    /// After the first step reaching each multiple of this time.
    pub every_time: Option<f64>,
    /// After the first step reaching each of these times (ascending).
    pub at: Vec<f64>,
    /// Next multiple of `every_time` and next index into `at` still to come.
    next_time: f64,
    next_at: usize,
}

impl Schedule {
    /// A schedule of the given parts, for a run resumed at time `t0` (times
    /// up to `t0` are taken as done: a restarted run does not repeat the
    /// outputs of its first part); `f64::NEG_INFINITY` for a fresh run.
    pub fn new(
        every_steps: Option<u64>,
        every_time: Option<f64>,
        mut at: Vec<f64>,
        t0: f64,
    ) -> Self {
        at.sort_by(f64::total_cmp);
        let mut s = Schedule {
            every_steps,
            every_time,
            at,
            next_time: f64::INFINITY,
            next_at: 0,
        };
        s.skip_to(t0);
        s
    }

    /// Whether the schedule has any part.
    pub fn is_active(&self) -> bool {
        self.every_steps.is_some() || self.every_time.is_some() || !self.at.is_empty()
    }

    fn skip_to(&mut self, t: f64) {
        if t == f64::NEG_INFINITY {
            // A fresh run: nothing is done yet.
            self.next_time = self.every_time.unwrap_or(f64::INFINITY);
            return;
        }
        if let Some(dt) = self.every_time {
            // The first multiple of dt after t.
            let mut k = (t / dt).floor();
            while k * dt <= t {
                k += 1.0;
            }
            self.next_time = k * dt;
        }
        while self.next_at < self.at.len() && self.at[self.next_at] <= t {
            self.next_at += 1;
        }
    }

    /// The earliest requested time (a multiple of `every_time` or an entry
    /// of `at`) that `t` reaches and that is not done yet: the time a
    /// block-step run's snapshot is predicted to. Ask before
    /// [`due`](Self::due), which marks it done.
    pub fn time_due(&self, t: f64) -> Option<f64> {
        let by_time = (self.every_time.is_some() && t >= self.next_time * (1.0 - 1e-12))
            .then_some(self.next_time);
        let by_list = self
            .at
            .get(self.next_at)
            .copied()
            .filter(|&a| t >= a * (1.0 - 1e-12));
        match (by_time, by_list) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Whether an output is due after `step` (reaching time `t`); advances
    /// past every time reached.
    pub fn due(&mut self, step: u64, t: f64) -> bool {
        let by_step = self.every_steps.is_some_and(|n| step.is_multiple_of(n));
        let by_time = self.every_time.is_some() && t >= self.next_time * (1.0 - 1e-12);
        let by_list = self
            .at
            .get(self.next_at)
            .is_some_and(|&a| t >= a * (1.0 - 1e-12));
        if by_time || by_list {
            // Everything up to t (with the same tolerance) is done.
            self.skip_to(t * (1.0 + 1e-12));
        }
        by_step || by_time || by_list
    }
}

/// Converts a box to the file's form.
pub fn box_spec(b: &BoundingBox) -> BoxSpec {
    BoxSpec {
        lo: b.lo(),
        hi: b.hi(),
        periodic: std::array::from_fn(|k| b.is_periodic(k)),
    }
}

/// Converts a file's box back.
pub fn bounding_box(b: &BoxSpec) -> Result<BoundingBox, AppError> {
    let boundary = b.periodic.map(|p| {
        if p {
            Boundary::Periodic
        } else {
            Boundary::Open
        }
    });
    Ok(BoundingBox::new(b.lo, b.hi, boundary)?)
}

/// An I/O error of the snapshot files as an [`AppError`].
pub fn io_error(e: IoError) -> AppError {
    AppError::Snapshot(e)
}

/// Writes `local` (this rank's rows; its metadata and attributes must be
/// the same on every rank) as step group 0 of a new file `path`, every rank
/// its own rows, in rank order (see the [module docs](self)). Collective.
/// Returns the longest time a rank spent, in seconds.
///
/// # Errors
/// On every rank when any rank failed (each failing rank names its cause;
/// the others say which rank failed).
pub fn write<C: Communicator>(comm: &C, path: &Path, local: &Snapshot) -> Result<f64, AppError> {
    write_then_commit(comm, path, local, || Ok(()))
}

/// As [`write()`], running `before_commit` on rank 0 when every rank's
/// rows are on disk in `NAME.tmp`, before it is renamed to `NAME` (an
/// error there fails the write on every rank).
pub(crate) fn write_then_commit<C: Communicator>(
    comm: &C,
    path: &Path,
    local: &Snapshot,
    before_commit: impl FnOnce() -> Result<(), AppError>,
) -> Result<f64, AppError> {
    let start = std::time::Instant::now();
    let rank = comm.rank();
    let fail = |what: &str| {
        AppError::Usage(format!(
            "{}: another rank failed to {what} (see its message)",
            path.display()
        ))
    };
    // 1. Summaries: rows and per-field checksum parts, to every rank.
    let summary = SlabSummary::of(local, &Selection::All);
    let mut words: Vec<u64> = vec![u64::from(summary.is_err())];
    if let Ok(s) = &summary {
        words.push(s.rows);
        for (_, _, c) in &s.fields {
            words.extend([u64::from(c.crc32), c.bytes]);
        }
    }
    let got = comm.all_gather_v(&words)?;
    let summary = summary.map_err(io_error)?;
    let mut summaries = Vec::with_capacity(comm.size());
    for r in 0..comm.size() {
        let w = got.from_rank(r);
        if w.first() != Some(&0) || w.len() != 2 + 2 * summary.fields.len() {
            return Err(fail("summarise its particles"));
        }
        summaries.push(SlabSummary {
            rows: w[1],
            fields: summary
                .fields
                .iter()
                .zip(w[2..].chunks_exact(2))
                .map(|((n, t, _), c)| {
                    (
                        n.clone(),
                        *t,
                        slab::PartialCrc {
                            crc32: c[0] as u32,
                            bytes: c[1],
                        },
                    )
                })
                .collect(),
        });
    }
    let first_row: u64 = summaries[..rank].iter().map(|s| s.rows).sum();
    // 2. Rank 0 lays the file out and tells everyone where the values go.
    let mut layout: Result<Vec<u64>, IoError> = Ok(Vec::new());
    let mut offsets = vec![0u64; summary.fields.len() + 1];
    if rank == 0 {
        layout = slab::create_layout(path, local, &summaries);
        match &layout {
            Ok(o) => offsets[1..].copy_from_slice(o),
            Err(_) => offsets[0] = 1,
        }
    }
    let sent = comm.all_gather_v(&if rank == 0 { offsets } else { Vec::new() })?;
    layout.map_err(io_error)?;
    let offsets = sent.from_rank(0).to_vec();
    if offsets.first() != Some(&0) {
        return Err(fail("lay out the file"));
    }
    // 3. Every rank writes its rows; all agree on success; rank 0 commits.
    let written = slab::write_slab(path, &offsets[1..], first_row, local, &Selection::All);
    let failed = comm.all_reduce_scalar(u64::from(written.is_err()), ReduceOp::Max);
    written.map_err(io_error)?;
    if failed > 0 {
        return Err(fail("write its rows"));
    }
    let mut committed = Ok(());
    if rank == 0 {
        committed = before_commit().and_then(|()| slab::commit(path).map_err(io_error));
    }
    let failed = comm.all_reduce_scalar(u64::from(committed.is_err()), ReduceOp::Max);
    committed?;
    if failed > 0 {
        return Err(fail("commit the file"));
    }
    Ok(comm.all_reduce_scalar(start.elapsed().as_secs_f64(), ReduceOp::Max))
}

/// This rank's share of step group `index` of `path`: rows `total * r / R
/// .. total * (r + 1) / R` of the fields `select` names, with the metadata;
/// the whole file is checked (every rank's partial checksums combined).
/// Collective. Returns the snapshot and the total row count.
///
/// # Errors
/// On every rank when any rank's read or the combined checksum failed.
pub fn read_share<C: Communicator>(
    comm: &C,
    path: &Path,
    index: usize,
    select: &Selection,
) -> Result<(Snapshot, u64), AppError> {
    let (r, size) = (
        u128::from(comm.rank() as u64),
        u128::from(comm.size() as u64),
    );
    // The total first (metadata only), then this rank's rows.
    let read = slab::read_rows(path, index, select, 0..0)
        .map_err(io_error)
        .and_then(|(head, n, _)| {
            check_fits(path, index, head.fields.len(), n)?;
            // In u128: n r does not overflow (the quotients fit in u64).
            let at = |r: u128| (u128::from(n) * r / size) as u64;
            slab::read_rows(path, index, select, at(r)..at(r + 1)).map_err(io_error)
        });
    let mut words = vec![u64::from(read.is_err())];
    if let Ok((_, _, checks)) = &read {
        words.extend(slab::checks_to_words(checks));
    }
    let got = comm.all_gather_v(&words)?;
    let (snap, n, checks) = read?;
    let mut parts = Vec::with_capacity(comm.size());
    for k in 0..comm.size() {
        let w = got.from_rank(k);
        if w.first() != Some(&0) {
            return Err(AppError::Usage(format!(
                "{}: rank {k} could not read its rows (see its message)",
                path.display()
            )));
        }
        parts.push(slab::checks_from_words(&checks, &w[1..]));
    }
    slab::verify(path, index, &parts).map_err(io_error)?;
    Ok((snap, n))
}

/// Refuses step group `index` of `path` when its `n` rows of `fields`
/// 8-byte fields need more bytes than the file holds (a damaged or forged
/// count), before anything is allocated for them.
fn check_fits(path: &Path, index: usize, fields: usize, n: u64) -> Result<(), AppError> {
    let len = std::fs::metadata(path)
        .map_err(|e| AppError::io(path, e))?
        .len();
    let need = n.checked_mul(8).and_then(|b| b.checked_mul(fields as u64));
    if need.is_some_and(|b| b <= len) {
        return Ok(());
    }
    Err(AppError::Usage(format!(
        "{}: Step#{index} claims {n} particles, {} bytes of values in its {fields} fields, \
         but the file holds {len} bytes (truncated or damaged)",
        path.display(),
        need.map_or("more than 2^64".to_string(), |b| b.to_string()),
    )))
}

/// `DIR/NAME_SSSSSSSS.h5` for step `step`.
pub fn numbered(dir: &Path, name: &str, step: u64) -> PathBuf {
    dir.join(format!("{name}_{step:08}.h5"))
}

/// Adds attribute `name` (string) to `snap`.
pub fn set_str(snap: &mut Snapshot, name: &str, value: &str) {
    snap.set_attr(name, Attr::Str(value.to_owned()));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_fire_once_per_step_and_skip_what_a_restart_has_done() {
        let mut s = Schedule::new(Some(3), None, vec![], f64::NEG_INFINITY);
        let fired: Vec<u64> = (1..=10).filter(|&k| s.due(k, k as f64)).collect();
        assert_eq!(fired, vec![3, 6, 9]);
        // Every 0.25 in time, steps of 0.1: first step at or past each multiple.
        let mut s = Schedule::new(None, Some(0.25), vec![], f64::NEG_INFINITY);
        let fired: Vec<u64> = (1..=10).filter(|&k| s.due(k, k as f64 * 0.1)).collect();
        assert_eq!(fired, vec![3, 5, 8, 10]);
        // A long step past several multiples fires once.
        let mut s = Schedule::new(None, Some(0.1), vec![], f64::NEG_INFINITY);
        assert!(!s.due(1, 0.0));
        assert!(s.due(1, 0.35));
        assert!(!s.due(2, 0.38));
        assert!(s.due(3, 0.4));
        // Listed times, unsorted; a restart at t = 0.5 skips those before.
        let mut s = Schedule::new(None, None, vec![0.7, 0.2, 0.5], 0.5);
        let fired: Vec<u64> = (6..=10).filter(|&k| s.due(k, k as f64 * 0.1)).collect();
        assert_eq!(fired, vec![7]);
        assert!(!Schedule::default().is_active());
        // A fresh run writes a snapshot listed at t = 0 after its first step.
        let mut s = Schedule::new(None, None, vec![0.0], f64::NEG_INFINITY);
        assert!(s.due(1, 1e-6));
        assert!(!s.due(2, 2e-6));
    }

    #[test]
    fn field_lists_name_what_is_wrong() {
        assert_eq!(parse_fields("x, rho,id").unwrap(), ["x", "rho", "id"]);
        let e = parse_fields("x,density").unwrap_err();
        assert!(e.contains("'density'") && e.contains("rho"), "{e}");
        assert!(parse_fields("x,x").unwrap_err().contains("twice"));
    }
}
