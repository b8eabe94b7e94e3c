//! `timings.csv` and the timing figures of the summary: seconds per stage
//! (one column per name of [`STAGES`]) and decomposition figures, per
//! synchronisation step (every step of a global run, the sub-steps between
//! two points where every particle is active under block time steps) and
//! as means over rows 2..N (row 1 holds set-up costs).

use super::observer::{Observed, StepObserver, StepView};
use super::CsvFile;
use crate::AppError;
use sph_core::{StepReport, STAGES};
use std::path::Path;

pub use super::totals::{DomainSummary, StageTotals};

/// The open `timings.csv` (rank 0), or a rank's `timings.rankR.csv`: a
/// row per synchronisation step (every step of a global run; under block
/// time steps the sub-steps from one point where every particle is active
/// to the next), with its sub-steps' totals.
#[derive(Debug)]
pub struct TimingsCsv {
    file: CsvFile,
    /// The synchronisation step in progress.
    row: RowSums,
    /// Rows written.
    rows: u64,
    /// Sums of rows 2..N (the first carries set-up costs).
    sums: RowSums,
}

/// The summed columns of a row (or of several).
#[derive(Debug, Clone, Copy, Default)]
struct RowSums {
    /// The first (sub-)step of the row.
    first_step: u64,
    stages: [f64; STAGES.len()],
    substeps: u64,
    updates: u64,
    bytes_sent: u64,
    comm_s: f64,
    sync_s: f64,
}

impl RowSums {
    fn add(&mut self, o: &RowSums) {
        for (a, b) in self.stages.iter_mut().zip(o.stages) {
            *a += b;
        }
        self.substeps += o.substeps;
        self.updates += o.updates;
        self.bytes_sent += o.bytes_sent;
        self.comm_s += o.comm_s;
        self.sync_s += o.sync_s;
    }

    fn total(&self) -> f64 {
        self.stages.iter().sum()
    }
}

impl TimingsCsv {
    /// Creates the file and writes the header (`step`, the stage names,
    /// `total`, the decomposition columns, `substeps`, `updates`,
    /// `dt_limit`).
    pub fn create(path: &Path) -> Result<Self, AppError> {
        let mut f = CsvFile::create(path)?;
        f.line(&format!(
            "step,{},total,owned_min,owned_max,halo_ratio,halo_ratio_max,bytes_sent,comm_s_max,sync_s_max,substeps,updates,dt_limit",
            STAGES.join(",")
        ))?;
        Ok(Self {
            file: f,
            row: RowSums::default(),
            rows: 0,
            sums: RowSums::default(),
        })
    }

    /// Adds (sub-)step `r`; at the end of a synchronisation step writes
    /// its row: the stages, bytes and communication seconds summed over
    /// its sub-steps, the decomposition figures and the criterion of the
    /// last one. `totals` gives the halo-ratio denominator.
    pub fn step(&mut self, r: &StepReport, totals: &StageTotals) -> Result<(), AppError> {
        let d = r.domain;
        if self.row.substeps == 0 {
            self.row.first_step = r.step;
        }
        self.row.add(&RowSums {
            first_step: r.step,
            stages: r.times.0,
            substeps: 1,
            updates: r.updates,
            bytes_sent: d.bytes_sent,
            comm_s: d.comm_seconds_max,
            sync_s: d.sync_seconds_max,
        });
        if !r.ends_synchronised {
            return Ok(());
        }
        let row = std::mem::take(&mut self.row);
        let times: Vec<String> = row.stages.iter().map(|s| format!("{s:.6e}")).collect();
        self.file.line_fmt(format_args!(
            "{},{},{:.6e},{},{},{:.6e},{:.6e},{},{:.6e},{:.6e},{},{},{}",
            row.first_step,
            times.join(","),
            row.total(),
            d.owned_min,
            d.owned_max,
            totals.halo_ratio(r),
            d.halo_ratio_max,
            row.bytes_sent,
            row.comm_s,
            row.sync_s,
            row.substeps,
            row.updates,
            r.dt_limit.name()
        ))?;
        self.rows += 1;
        if self.rows >= 2 {
            self.sums.add(&row);
        }
        Ok(())
    }

    /// Writes out what is buffered (at the end of the loop).
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.file.flush()
    }

    /// The last line, `mean_2..N`: the means over rows 2..N (the only
    /// row's values if there is one) of the summed columns, and the
    /// decomposition's means over (sub-)steps 2..N; then closes the file.
    /// The line ends before the text column `dt_limit`, which has no mean,
    /// so a reader that zips it with the header and parses every field as
    /// a number (`docs/bench/side-by-side`) never meets text. A run that
    /// stopped inside a synchronisation step (`--steps`) has no row for
    /// that part.
    pub fn finish(mut self, totals: &StageTotals) -> Result<(), AppError> {
        let (mean, n) = if self.rows >= 2 {
            (self.sums, (self.rows - 1) as f64)
        } else {
            (self.sums_of_the_only_row(totals), 1.0)
        };
        let means: Vec<String> = mean
            .stages
            .iter()
            .map(|s| format!("{:.6e}", s / n))
            .collect();
        let dom = totals.domain();
        self.file.line_fmt(format_args!(
            "mean_2..N,{},{:.6e},{},{},{:.6e},{:.6e},{:.0},{:.6e},{:.6e},{:.3},{:.1}",
            means.join(","),
            mean.total() / n,
            dom.owned_min,
            dom.owned_max,
            dom.halo_ratio_mean,
            dom.halo_ratio_max,
            mean.bytes_sent as f64 / n,
            mean.comm_s / n,
            mean.sync_s / n,
            mean.substeps as f64 / n,
            mean.updates as f64 / n
        ))?;
        self.file.flush()
    }

    /// A run of one row or none: the stage means of `totals` (the only
    /// step's times, or NaN), as before block steps.
    fn sums_of_the_only_row(&self, totals: &StageTotals) -> RowSums {
        let mut r = RowSums {
            substeps: 1,
            ..RowSums::default()
        };
        r.stages.copy_from_slice(&totals.stage_means());
        r.updates = totals.mean_updates() as u64;
        r
    }
}

impl<C> StepObserver<C> for TimingsCsv {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        TimingsCsv::step(self, view.report, view.totals)?;
        Ok(Observed::Recorded)
    }

    fn flush(&mut self) -> Result<(), AppError> {
        TimingsCsv::flush(self)
    }
}

/// A rank's own `timings.rankR.csv` (ranks but 0, with `--rank-timings`):
/// a diagnostic, so an error warns and ends the file, never the run (and
/// never leaves the other ranks waiting in a collective).
#[derive(Debug)]
pub struct RankTimings(Option<TimingsCsv>);

impl RankTimings {
    /// `OUT/timings.rankR.csv` of rank `rank`, or a warning and no file.
    pub fn open(out: &Path, rank: usize) -> Self {
        let path = out.join(format!("timings.rank{rank}.csv"));
        let file = std::fs::create_dir_all(out)
            .map_err(|e| AppError::io(out, e))
            .and_then(|()| TimingsCsv::create(&path));
        match file {
            Ok(f) => Self(Some(f)),
            Err(e) => {
                eprintln!("warning: {e}; rank {rank} writes no timings");
                Self(None)
            }
        }
    }
}

impl<C> StepObserver<C> for RankTimings {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        if let Some(file) = self.0.as_mut() {
            if let Err(e) = file.step(view.report, view.totals) {
                eprintln!("warning: {e}; this rank's timings stop here");
                self.0 = None;
            }
        }
        Ok(Observed::Recorded)
    }

    fn ended(&mut self, totals: &StageTotals) {
        if let Some(Err(e)) = self.0.take().map(|file| file.finish(totals)) {
            eprintln!("warning: {e}");
        }
    }
}
