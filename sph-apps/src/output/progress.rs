//! Progress of a run on stderr: a bar on a terminal, a log line every few
//! seconds otherwise.

use super::observer::{Observed, StepObserver, StepView};
use super::totals::StageTotals;
use crate::AppError;
use sph_core::StepReport;
use std::io::IsTerminal;
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

/// Reports the steps of a run (rank 0 only; other ranks pass
/// [`Progress::Quiet`]).
#[derive(Debug)]
pub struct ProgressReporter {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
    stop: Stop,
    last_log: Instant,
}

impl ProgressReporter {
    /// A reporter for a run until `stop`.
    pub fn new(progress: Progress, stop: Stop) -> Self {
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
            last_log: Instant::now(),
        }
    }

    /// Reports step `r`, after which the time is `t_now`.
    pub fn update(&mut self, r: &StepReport, t_now: f64) {
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
        } else if self.last_log.elapsed().as_secs_f64() > 5.0 || r.step == 1 {
            self.last_log = Instant::now();
            eprintln!("{msg}");
        }
    }

    /// Completes the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish();
        }
    }
}

/// The progress of rank 0's run. A stop by the watch (a bound crossed,
/// non-finite sums) leaves the bar on the terminal at the last step that
/// passed; any other error clears it.
impl<C> StepObserver<C> for ProgressReporter {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        self.update(view.report, view.state.t);
        Ok(Observed::Recorded)
    }

    fn stopped(&mut self, error: &AppError) {
        if matches!(error, AppError::Watch(_) | AppError::NonFinite { .. }) {
            ProgressReporter::finish(self);
        }
    }

    fn ended(&mut self, _totals: &StageTotals) {
        ProgressReporter::finish(self);
    }
}
