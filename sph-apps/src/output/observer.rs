//! The per-step outputs of a run as observers: the run loop hands every
//! observer each step in turn ([`StepObserver::step`]), tells them when a
//! checkpoint made the step a restart point, and when the loop ended.
//! The writers (`conserved.csv`, `timings.csv`, `timings.rankR.csv`,
//! `curve.csv`, snapshots and checkpoints), the watch of the conserved
//! quantities and the progress report each implement it next to their own
//! code.

use super::totals::StageTotals;
use crate::AppError;
use sph_core::hydro::predict_field;
use sph_core::{BlockRun, Particles, RunState, StepReport};
use sph_tree::BoundingBox;
use std::borrow::Cow;
use std::ops::Range;

/// What the observers see after a step (the same on every rank but the
/// particles, which are this rank's).
#[derive(Debug)]
pub struct StepView<'a, C> {
    /// The step's report.
    pub report: &'a StepReport,
    /// The stage totals, this step included.
    pub totals: &'a StageTotals,
    /// The run state after the step (steps done, time, last step).
    pub state: RunState,
    /// This rank's particles after the step (halos included).
    pub particles: &'a Particles,
    /// Range of this rank's own particles in `particles`.
    pub owned: Range<usize>,
    /// The box after the step.
    pub bbox: &'a BoundingBox,
    /// The ranks of the run.
    pub comm: &'a C,
    /// Particles of the whole run (all ranks).
    pub total: usize,
    /// The driving state after the step (stirred runs).
    pub stirring: Option<&'a sph_core::stirring::Stirring>,
}

impl<C> StepView<'_, C> {
    /// Where an output due at the requested time `t_due` (which this step
    /// reached) is taken under block time steps: the run's time line and
    /// that time, no earlier than the sub-step's start. `None` for a
    /// global run or an output not due at a time: the state after the step.
    pub fn output_time(&self, t_due: Option<f64>) -> Option<(BlockRun, f64)> {
        self.state
            .block
            .zip(t_due)
            .map(|(b, t_out)| (b, t_out.clamp(self.report.t, self.state.t)))
    }

    /// The owned particles' `values` of the field `name` at `at` (from
    /// [`Self::output_time`]): predicted back within the sub-step for the
    /// fields [`sph_core::hydro::PREDICTED`] names, as they are otherwise.
    ///
    /// # Errors
    /// A state that cannot be predicted ([`predict_field`]).
    pub fn owned_at<'v>(
        &self,
        name: &str,
        values: &'v [f64],
        at: Option<(BlockRun, f64)>,
    ) -> Result<Cow<'v, [f64]>, AppError> {
        let own = &values[self.owned.clone()];
        match at {
            None => Ok(Cow::Borrowed(own)),
            Some(_) => {
                let mut v = own.to_vec();
                self.predict_owned(name, &mut v, at)?;
                Ok(Cow::Owned(v))
            }
        }
    }

    /// Moves `v`, the owned particles' values of the field `name` after
    /// the step, to `at` (from [`Self::output_time`]) in place: the fields
    /// [`sph_core::hydro::PREDICTED`] names are predicted back within the
    /// sub-step, the others and every field of a global run stay.
    ///
    /// # Errors
    /// A state that cannot be predicted ([`predict_field`]).
    pub fn predict_owned(
        &self,
        name: &str,
        v: &mut [f64],
        at: Option<(BlockRun, f64)>,
    ) -> Result<(), AppError> {
        if let Some((b, t_out)) = at {
            let (p, r) = (self.particles, self.owned.clone());
            predict_field(p, r, self.bbox, &b, self.state.t, t_out, name, v)?;
        }
        Ok(())
    }
}

/// What an observer made of a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Observed {
    /// Recorded it (or nothing was due).
    Recorded,
    /// Wrote a checkpoint of it: the others then flush
    /// ([`StepObserver::flush`]), so that a run killed later resumes from
    /// files that hold every line up to it.
    Checkpoint,
}

/// One output of a run, told of every step. Collective where its
/// implementation says so: every rank holds the same observers in the
/// same order (those of rank 0's files do nothing elsewhere).
pub trait StepObserver<C> {
    /// After every step, in the order of the run's observers; an error
    /// stops the run.
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError>;

    /// A checkpoint of the step is complete: write out what is buffered.
    fn flush(&mut self) -> Result<(), AppError> {
        Ok(())
    }

    /// An observer stopped the run with `error` after a step.
    fn stopped(&mut self, _error: &AppError) {}

    /// The loop ended, with stage totals `totals`: close what cannot fail
    /// the run (warnings only), before any observer
    /// [`finish`](Self::finish)es.
    fn ended(&mut self, _totals: &StageTotals) {}

    /// The loop ended: write out what is buffered (and what is drawn from
    /// it).
    fn finish(&mut self) -> Result<(), AppError> {
        self.flush()
    }
}

/// An observer lent to the run (the run's owner reads it afterwards).
impl<C, T: StepObserver<C>> StepObserver<C> for &mut T {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        (**self).step(view)
    }

    fn flush(&mut self) -> Result<(), AppError> {
        (**self).flush()
    }

    fn stopped(&mut self, error: &AppError) {
        (**self).stopped(error)
    }

    fn ended(&mut self, totals: &StageTotals) {
        (**self).ended(totals)
    }

    fn finish(&mut self) -> Result<(), AppError> {
        (**self).finish()
    }
}

/// Hands step `view` to every observer in order; when one wrote a
/// checkpoint, all then flush in order. The first error stops the round,
/// and every observer is told of it.
///
/// # Errors
/// The first observer's error.
pub fn notify<C>(
    observers: &mut [Box<dyn StepObserver<C> + '_>],
    view: &StepView<'_, C>,
) -> Result<(), AppError> {
    let mut checkpoint = false;
    let round = observers.iter_mut().try_for_each(|o| {
        checkpoint |= o.step(view)? == Observed::Checkpoint;
        Ok::<(), AppError>(())
    });
    if let Err(e) = round {
        for o in observers.iter_mut() {
            o.stopped(&e);
        }
        return Err(e);
    }
    if checkpoint {
        for o in observers.iter_mut() {
            o.flush()?;
        }
    }
    Ok(())
}
