//! `curve.csv` and `curve.png`: a case's tracked observable
//! ([`Curve`]) at every step.

use super::observer::{Observed, StepObserver, StepView};
use super::CsvFile;
use crate::analysis;
use crate::cases::Curve;
use crate::AppError;
use plotters::style::RGBColor;
use sph_comm::Communicator;
use std::path::{Path, PathBuf};

/// The open `curve.csv` and the samples written so far (for the plot).
#[derive(Debug)]
pub struct CurveCsv {
    file: CsvFile,
    curve: Curve,
    samples: Vec<(f64, Vec<f64>)>,
}

impl CurveCsv {
    fn header(curve: &Curve) -> String {
        format!("step,t,{}", curve.columns.join(","))
    }

    /// Creates `path` with the header of `curve`.
    pub fn create(path: &Path, curve: Curve) -> Result<Self, AppError> {
        let mut file = CsvFile::create(path)?;
        file.line(&Self::header(&curve))?;
        Ok(Self {
            file,
            curve,
            samples: Vec::new(),
        })
    }

    /// Reopens `path` for a run resumed after `last_step`: keeps the
    /// complete lines of the steps up to it (a run killed after a
    /// checkpoint may have written later ones) and the samples they hold.
    pub fn resume(path: &Path, curve: Curve, last_step: u64) -> Result<Self, AppError> {
        let old = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
            Err(e) => return Err(AppError::io(path, e)),
        };
        let mut me = Self::create(path, curve)?;
        let width = 2 + curve.columns.len();
        for line in old.lines().skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            let step = f[0].parse::<u64>().ok();
            let values: Option<Vec<f64>> = f.iter().skip(1).map(|v| v.parse().ok()).collect();
            if let (Some(step), Some(values), true) = (step, values, f.len() == width) {
                if step <= last_step {
                    me.file.line(line)?;
                    me.samples.push((values[0], values[1..].to_vec()));
                }
            }
        }
        Ok(me)
    }

    /// One line: the values at `step`, time `t`.
    pub fn push(&mut self, step: u64, t: f64, values: Vec<f64>) -> Result<(), AppError> {
        let mut line = format!("{step},{t:.17e}");
        for v in &values {
            line.push_str(&format!(",{v:.17e}"));
        }
        self.file.line(&line)?;
        self.samples.push((t, values));
        Ok(())
    }

    /// Writes out what is buffered.
    pub fn flush(&mut self) -> Result<(), AppError> {
        self.file.flush()
    }

    /// `curve.png`: every column against time, the reference as markers.
    pub fn plot(&self, path: &Path, title: &str) -> Result<(), AppError> {
        let colours = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
            RGBColor(0, 0, 0),
        ];
        let columns: Vec<Vec<(f64, f64)>> = (0..self.curve.columns.len())
            .map(|k| self.samples.iter().map(|(t, v)| (*t, v[k])).collect())
            .collect();
        let series: Vec<_> = self
            .curve
            .columns
            .iter()
            .zip(&columns)
            .enumerate()
            .map(|(k, (name, pts))| (*name, colours[k % colours.len()], pts.as_slice()))
            .collect();
        let reference = [("reference", colours[0], self.curve.reference)];
        let reference = if self.curve.reference.is_empty() {
            &reference[..0]
        } else {
            &reference[..]
        };
        crate::plot::series_png(path, title, self.curve.label, &series, reference)
    }
}

/// A case's tracked observable after every step: reduced over the ranks
/// (collective: every rank holds one), written by rank 0 into
/// `curve.csv`, and plotted as `curve.png` at the end.
#[derive(Debug)]
pub struct CurveObserver {
    curve: Curve,
    /// Rank 0's file.
    file: Option<CurveCsv>,
    /// `curve.png` and its title.
    plot: (PathBuf, String),
}

impl CurveObserver {
    /// The observer of `curve`, writing `file` (rank 0's, `None`
    /// elsewhere); `plot` is `curve.png`'s path and title.
    pub fn new(curve: Curve, file: Option<CurveCsv>, plot: (PathBuf, String)) -> Self {
        Self { curve, file, plot }
    }
}

impl<C: Communicator> StepObserver<C> for CurveObserver {
    fn step(&mut self, view: &StepView<'_, C>) -> Result<Observed, AppError> {
        let values =
            analysis::curve_values(view.particles, view.owned.clone(), view.comm, &self.curve);
        // The values are of the particles after the step.
        if let Some(file) = self.file.as_mut() {
            file.push(view.report.step, view.state.t, values)?;
        }
        Ok(Observed::Recorded)
    }

    fn flush(&mut self) -> Result<(), AppError> {
        self.file.as_mut().map_or(Ok(()), CurveCsv::flush)
    }

    fn finish(&mut self) -> Result<(), AppError> {
        if let Some(file) = self.file.as_mut() {
            file.flush()?;
            file.plot(&self.plot.0, &self.plot.1)?;
        }
        Ok(())
    }
}
