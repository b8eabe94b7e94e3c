//! `timings.csv` and the timing figures of the summary: seconds per stage
//! (one column per name of [`STAGES`]) and decomposition figures, per step
//! and as means over steps 2..N (step 1 holds set-up costs).

use super::observer::{Observed, StepObserver, StepView};
use super::CsvFile;
use crate::AppError;
use sph_core::{StepReport, STAGES};
use std::path::Path;

pub use super::totals::{DomainSummary, StageTotals};

/// The open `timings.csv` (rank 0), or a rank's `timings.rankR.csv`.
#[derive(Debug)]
pub struct TimingsCsv(CsvFile);

impl TimingsCsv {
    /// Creates the file and writes the header (`step`, the stage names,
    /// `total`, the decomposition columns).
    pub fn create(path: &Path) -> Result<Self, AppError> {
        let mut f = CsvFile::create(path)?;
        f.line(&format!(
            "step,{},total,owned_min,owned_max,halo_ratio,halo_ratio_max,bytes_sent,comm_s_max,sync_s_max,updates,dt_limit",
            STAGES.join(",")
        ))?;
        Ok(Self(f))
    }

    /// One line for step `r`; `totals` gives the halo-ratio denominator.
    pub fn step(&mut self, r: &StepReport, totals: &StageTotals) -> Result<(), AppError> {
        let times: Vec<String> = r.times.0.iter().map(|s| format!("{s:.6e}")).collect();
        let d = r.domain;
        self.0.line_fmt(format_args!(
            "{},{},{:.6e},{},{},{:.6e},{:.6e},{},{:.6e},{:.6e},{},{}",
            r.step,
            times.join(","),
            r.times.total(),
            d.owned_min,
            d.owned_max,
            totals.halo_ratio(r),
            d.halo_ratio_max,
            d.bytes_sent,
            d.comm_seconds_max,
            d.sync_seconds_max,
            r.updates,
            r.dt_limit.name()
        ))
    }

    /// Writes out what is buffered (at the end of the loop).
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.0.flush()
    }

    /// The last line, `mean_2..N`: the means over steps 2..N; then closes
    /// the file. The line ends before the text column `dt_limit`, which has
    /// no mean, so a reader that zips it with the header and parses every
    /// field as a number (`docs/bench/side-by-side`) never meets text.
    pub fn finish(mut self, totals: &StageTotals) -> Result<(), AppError> {
        let means: Vec<String> = totals
            .stage_means()
            .iter()
            .map(|s| format!("{s:.6e}"))
            .collect();
        let dom = totals.domain();
        self.0.line_fmt(format_args!(
            "mean_2..N,{},{:.6e},{},{},{:.6e},{:.6e},{:.0},{:.6e},{:.6e},{:.1}",
            means.join(","),
            totals.mean_step_s(),
            dom.owned_min,
            dom.owned_max,
            dom.halo_ratio_mean,
            dom.halo_ratio_max,
            dom.bytes_sent_per_step,
            dom.comm_seconds_per_step,
            dom.sync_seconds_per_step,
            totals.mean_updates()
        ))?;
        self.0.flush()
    }
}

/// `timings.csv` (rank 0): a line per step; its last line, the means, is
/// written by [`TimingsCsv::finish`] among the run's final files.
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
