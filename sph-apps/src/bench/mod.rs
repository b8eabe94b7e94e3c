//! `sphexa bench`: error against run time. Every combination of case,
//! scheme, kernel, size and repeat runs as a fresh `sphexa run` process (so
//! the peak RSS it reports is its own), to the case's end time; the rows go
//! to `bench.csv` and `bench.json`, with the spread over repeats and the
//! fitted convergence order per series and L1 field, and to
//! `error_vs_time.png` (L1 against wall time, log-log, one panel per field).
//!
//! A reference file (`--reference`) is a CSV with the same header as
//! `bench.csv` (any subset of columns that includes `N`, `wall_s` and the
//! `l1_*` columns; `case`, `scheme`, `kernel` name its series): its points
//! are drawn over the plot.

mod sweep;

pub use sweep::Sweep;

use crate::plot::{BenchLine, BenchPanel};
use crate::AppError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Columns of `bench.csv`, in order.
pub const COLUMNS: [&str; 23] = [
    "case",
    "scheme",
    "kernel",
    "time_steps",
    "N",
    "side",
    "ranks",
    "threads",
    "repeat",
    "steps",
    "particle_updates",
    "t_end",
    "wall_s",
    "particle_steps_per_s",
    "peak_rss_bytes",
    "bytes_per_particle",
    "l1_rho",
    "l1_p",
    "l1_v",
    "energy_drift",
    "momentum_drift",
    "angular_momentum_drift",
    "violations",
];

/// The L1 fields, as (column, label on the plot).
pub const L1_FIELDS: [(&str, &str); 3] = [("l1_rho", "L1 ρ"), ("l1_p", "L1 P"), ("l1_v", "L1 |v|")];

/// One run of the benchmark (a row of `bench.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Case.
    pub case: String,
    /// Scheme preset (`case` = the case's own scheme).
    pub scheme: String,
    /// Kernel.
    pub kernel: String,
    /// Time-step mode (`global`, `block`, `kdk`; empty in a reference
    /// file without the column: taken as global).
    pub time_steps: String,
    /// Particles.
    #[serde(rename = "N")]
    pub n: u64,
    /// Particles per side asked for (0 when unknown, e.g. a reference file).
    pub side: u64,
    /// MPI ranks.
    pub ranks: u64,
    /// Threads per rank.
    pub threads: u64,
    /// Repeat index (0-based).
    pub repeat: u64,
    /// Steps run (sub-steps under block time steps).
    pub steps: u64,
    /// Particle updates (particles times steps in a global run; 0 when
    /// unknown).
    pub particle_updates: u64,
    /// Time reached.
    pub t_end: f64,
    /// Wall-clock seconds of the time-step loop.
    pub wall_s: f64,
    /// Particle-steps per second (steps 2..N).
    pub particle_steps_per_s: f64,
    /// Peak resident memory of the run's process as the OS counts it.
    pub peak_rss_bytes: u64,
    /// Solver buffers per particle.
    pub bytes_per_particle: f64,
    /// L1 of density (NaN without a reference).
    pub l1_rho: f64,
    /// L1 of pressure.
    pub l1_p: f64,
    /// L1 of speed.
    pub l1_v: f64,
    /// Relative energy drift.
    pub energy_drift: f64,
    /// Relative momentum drift.
    pub momentum_drift: f64,
    /// Relative angular-momentum drift.
    pub angular_momentum_drift: f64,
    /// Bounds the run's watch saw crossed.
    pub violations: u64,
}

impl Row {
    /// The value of an L1 column.
    pub fn l1(&self, column: &str) -> f64 {
        match column {
            "l1_rho" => self.l1_rho,
            "l1_p" => self.l1_p,
            "l1_v" => self.l1_v,
            _ => f64::NAN,
        }
    }

    /// The series the row belongs to: case, scheme, kernel, and the
    /// time-step mode unless global.
    pub fn series(&self) -> String {
        let s = format!("{} {} {}", self.case, self.scheme, self.kernel);
        match self.time_steps.as_str() {
            "" | "global" => s,
            mode => format!("{s} {mode}"),
        }
    }

    /// The row's CSV line (full precision, in [`COLUMNS`] order).
    pub fn csv(&self) -> String {
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{}",
            self.case,
            self.scheme,
            self.kernel,
            self.time_steps,
            self.n,
            self.side,
            self.ranks,
            self.threads,
            self.repeat,
            self.steps,
            self.particle_updates,
            self.t_end,
            self.wall_s,
            self.particle_steps_per_s,
            self.peak_rss_bytes,
            self.bytes_per_particle,
            self.l1_rho,
            self.l1_p,
            self.l1_v,
            self.energy_drift,
            self.momentum_drift,
            self.angular_momentum_drift,
            self.violations
        )
    }

    /// The row of a run from its `summary.json`.
    ///
    /// # Errors
    /// A summary without the fields a run writes.
    pub fn from_summary(
        json: &serde_json::Value,
        scheme: &str,
        side: u64,
        repeat: u64,
        source: &Path,
    ) -> Result<Row, AppError> {
        let bad = |k: &str| {
            AppError::Usage(format!(
                "{}: no field '{k}' (not a summary.json of sphexa run?)",
                source.display()
            ))
        };
        let f = |k: &str| json[k].as_f64().ok_or_else(|| bad(k));
        let u = |k: &str| json[k].as_u64().ok_or_else(|| bad(k));
        let l1 = |k: &str| json["l1"][k].as_f64().unwrap_or(f64::NAN);
        Ok(Row {
            case: json["case"].as_str().ok_or_else(|| bad("case"))?.into(),
            scheme: scheme.into(),
            kernel: json["kernel"].as_str().ok_or_else(|| bad("kernel"))?.into(),
            // Summaries from before the mode was recorded are global runs.
            time_steps: json["time_steps"].as_str().unwrap_or("global").into(),
            n: u("particles")?,
            side,
            ranks: u("ranks")?,
            threads: u("threads")?,
            repeat,
            steps: u("steps")?,
            particle_updates: json["particle_updates"].as_u64().unwrap_or(0),
            t_end: f("t_end")?,
            wall_s: f("wall_s")?,
            particle_steps_per_s: f("particle_steps_per_s")?,
            peak_rss_bytes: u("peak_rss_bytes")?,
            bytes_per_particle: f("bytes_per_particle")?,
            l1_rho: l1("rho"),
            l1_p: l1("p"),
            l1_v: l1("v"),
            energy_drift: f("energy_rel_drift")?,
            momentum_drift: f("momentum_rel_drift")?,
            angular_momentum_drift: f("angular_momentum_rel_drift")?,
            violations: json["watch"]["violations"]
                .as_array()
                .map_or(0, |v| v.len() as u64),
        })
    }
}

/// Reads rows from a CSV with `bench.csv`'s header (any subset of its
/// columns that includes `N`, `wall_s` and at least one `l1_*`; missing
/// text columns are empty, missing numbers NaN or 0).
///
/// # Errors
/// An unreadable file, a header without those columns, or a number that
/// does not parse (named with its line and column).
pub fn read_csv(path: &Path) -> Result<Vec<Row>, AppError> {
    let text = std::fs::read_to_string(path).map_err(|e| AppError::io(path, e))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| AppError::Usage(format!("{}: empty file", path.display())))?
        .split(',')
        .map(str::trim)
        .collect();
    for need in ["N", "wall_s"] {
        if !header.contains(&need) {
            return Err(AppError::Usage(format!(
                "{}: no column '{need}'; a reference file has bench.csv's columns ({})",
                path.display(),
                COLUMNS.join(",")
            )));
        }
    }
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let cell = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .and_then(|i| cells.get(i).copied())
        };
        let num = |name: &str| -> Result<f64, AppError> {
            match cell(name) {
                None | Some("") => Ok(f64::NAN),
                Some(v) => v.parse::<f64>().map_err(|_| {
                    AppError::Usage(format!(
                        "{}: line {}: column {name} = '{v}' is not a number",
                        path.display(),
                        k + 2
                    ))
                }),
            }
        };
        let whole = |name: &str| -> Result<u64, AppError> {
            let x = num(name)?;
            Ok(if x.is_finite() && x >= 0.0 {
                x as u64
            } else {
                0
            })
        };
        let text = |name: &str| cell(name).unwrap_or("").to_string();
        rows.push(Row {
            case: text("case"),
            scheme: text("scheme"),
            kernel: text("kernel"),
            time_steps: text("time_steps"),
            n: whole("N")?,
            side: whole("side")?,
            ranks: whole("ranks")?,
            threads: whole("threads")?,
            repeat: whole("repeat")?,
            steps: whole("steps")?,
            particle_updates: whole("particle_updates")?,
            t_end: num("t_end")?,
            wall_s: num("wall_s")?,
            particle_steps_per_s: num("particle_steps_per_s")?,
            peak_rss_bytes: whole("peak_rss_bytes")?,
            bytes_per_particle: num("bytes_per_particle")?,
            l1_rho: num("l1_rho")?,
            l1_p: num("l1_p")?,
            l1_v: num("l1_v")?,
            energy_drift: num("energy_drift")?,
            momentum_drift: num("momentum_drift")?,
            angular_momentum_drift: num("angular_momentum_drift")?,
            violations: whole("violations")?,
        });
    }
    Ok(rows)
}

/// Least-squares slope of `y` against `x`; `None` with fewer than two
/// distinct `x`.
pub fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The fitted convergence of one series and field.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Order {
    /// Series (case, scheme, kernel).
    pub series: String,
    /// L1 column.
    pub field: String,
    /// Slope of log L1 against log N^(1/3) (negative when the error falls).
    pub slope: f64,
    /// Convergence order, -slope.
    pub order: f64,
    /// Resolutions fitted (N).
    pub sizes: Vec<u64>,
}

/// Wall time over the repeats of one series and size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    /// Series.
    pub series: String,
    /// Particles.
    #[serde(rename = "N")]
    pub n: u64,
    /// Repeats.
    pub repeats: usize,
    /// Shortest wall time.
    pub wall_s_min: f64,
    /// Median wall time.
    pub wall_s_median: f64,
    /// Peak RSS, median over repeats.
    pub peak_rss_bytes_median: u64,
}

/// The median of `v` (mean of the middle two for an even count).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Rows grouped by series, then by N (in ascending order).
pub fn grouped(rows: &[Row]) -> BTreeMap<String, BTreeMap<u64, Vec<&Row>>> {
    let mut g: BTreeMap<String, BTreeMap<u64, Vec<&Row>>> = BTreeMap::new();
    for r in rows {
        g.entry(r.series())
            .or_default()
            .entry(r.n)
            .or_default()
            .push(r);
    }
    g
}

/// The spread of wall times over the repeats of each series and size.
pub fn spreads(rows: &[Row]) -> Vec<Spread> {
    let mut out = Vec::new();
    for (series, by_n) in grouped(rows) {
        for (n, runs) in by_n {
            let mut walls: Vec<f64> = runs.iter().map(|r| r.wall_s).collect();
            let mut rss: Vec<f64> = runs.iter().map(|r| r.peak_rss_bytes as f64).collect();
            out.push(Spread {
                series: series.clone(),
                n,
                repeats: runs.len(),
                wall_s_min: walls.iter().copied().fold(f64::INFINITY, f64::min),
                wall_s_median: median(&mut walls),
                peak_rss_bytes_median: median(&mut rss) as u64,
            });
        }
    }
    out
}

/// The convergence order of every series and L1 field with at least two
/// sizes (L1 as the median over repeats).
pub fn orders(rows: &[Row]) -> Vec<Order> {
    let mut out = Vec::new();
    for (series, by_n) in grouped(rows) {
        for (field, _) in L1_FIELDS {
            let points: Vec<(u64, f64)> = by_n
                .iter()
                .map(|(n, runs)| {
                    let mut v: Vec<f64> = runs.iter().map(|r| r.l1(field)).collect();
                    (*n, median(&mut v))
                })
                .filter(|(n, l)| *n > 0 && l.is_finite() && *l > 0.0)
                .collect();
            let logs: Vec<(f64, f64)> = points
                .iter()
                .map(|(n, l)| ((*n as f64).cbrt().ln(), l.ln()))
                .collect();
            if let Some(s) = slope(&logs) {
                out.push(Order {
                    series: series.clone(),
                    field: field.into(),
                    slope: s,
                    order: -s,
                    sizes: points.iter().map(|p| p.0).collect(),
                });
            }
        }
    }
    out
}

/// Everything `bench.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Every run.
    pub runs: Vec<Row>,
    /// Wall-time spread over repeats.
    pub spread: Vec<Spread>,
    /// Fitted convergence orders.
    pub orders: Vec<Order>,
    /// The reference file's rows, if one was given.
    pub reference: Option<Vec<Row>>,
    /// Its path.
    pub reference_file: Option<PathBuf>,
}

impl Report {
    /// The report of `runs` (with `reference` points).
    pub fn new(runs: Vec<Row>, reference: Option<(PathBuf, Vec<Row>)>) -> Report {
        let (reference_file, reference) = match reference {
            Some((p, r)) => (Some(p), Some(r)),
            None => (None, None),
        };
        Report {
            spread: spreads(&runs),
            orders: orders(&runs),
            runs,
            reference,
            reference_file,
        }
    }

    /// Writes `bench.csv`, `bench.json` and `error_vs_time.png` into `out`.
    ///
    /// # Errors
    /// A file that cannot be written.
    pub fn write(&self, out: &Path, title: &str) -> Result<(), AppError> {
        std::fs::create_dir_all(out).map_err(|e| AppError::io(out, e))?;
        let mut csv = COLUMNS.join(",") + "\n";
        for r in &self.runs {
            csv += &r.csv();
            csv.push('\n');
        }
        let path = out.join("bench.csv");
        std::fs::write(&path, csv).map_err(|e| AppError::io(&path, e))?;
        let path = out.join("bench.json");
        let json = serde_json::to_string_pretty(self).expect("report serialises");
        std::fs::write(&path, json + "\n").map_err(|e| AppError::io(&path, e))?;
        crate::plot::bench_png(&out.join("error_vs_time.png"), title, &self.panels())
    }

    /// The plot's title: the cases of the runs, in order of their first
    /// row (repeats of a case in a row named once).
    pub fn title(&self) -> String {
        let mut names: Vec<String> = self.runs.iter().map(|r| r.case.clone()).collect();
        names.dedup();
        format!("L1 against wall time: {}", names.join(", "))
    }

    /// The table `sphexa bench` prints: per series and size the median
    /// wall time and a run's L1 errors, then the fitted orders (lines
    /// without the last newline).
    pub fn table(&self) -> String {
        let mut lines = vec![format!(
            "{:<28} {:>9} {:>6} {:>10} {:>10} {:>10} {:>10} {:>9}",
            "series", "N", "steps", "wall_s", "L1 rho", "L1 P", "L1 |v|", "RSS MB"
        )];
        for sp in &self.spread {
            let r = self
                .runs
                .iter()
                .find(|r| r.series() == sp.series && r.n == sp.n)
                .expect("a spread has runs");
            lines.push(format!(
                "{:<28} {:>9} {:>6} {:>10.3} {:>10.4e} {:>10.4e} {:>10.4e} {:>9.0}",
                sp.series,
                sp.n,
                r.steps,
                sp.wall_s_median,
                r.l1_rho,
                r.l1_p,
                r.l1_v,
                sp.peak_rss_bytes_median as f64 / 1e6
            ));
        }
        for o in &self.orders {
            lines.push(format!(
                "order {:<28} {:<7} {:.3} (sizes {:?})",
                o.series, o.field, o.order, o.sizes
            ));
        }
        lines.join("\n")
    }

    /// The panels of `error_vs_time.png`: per L1 field, one line per
    /// series (the median over repeats at each size, its fitted order in
    /// the legend) and the reference code's lines.
    fn panels(&self) -> Vec<BenchPanel> {
        let reference = self.reference.as_deref().unwrap_or(&[]);
        L1_FIELDS
            .iter()
            .map(|&(field, label)| {
                let runs = lines(&self.runs, field)
                    .into_iter()
                    .map(|(series, pts)| {
                        let order = self
                            .orders
                            .iter()
                            .find(|o| o.series == series && o.field == field)
                            .map_or(String::new(), |o| format!(" (order {:.2})", o.order));
                        (format!("{series}{order}"), pts)
                    })
                    .collect();
                BenchPanel {
                    label,
                    runs,
                    reference: lines(reference, field),
                }
            })
            .collect()
    }
}

/// (series, [(N, wall median, L1 median)]) of `rows` for `field`, the
/// points with a positive finite wall time and L1 only.
fn lines(rows: &[Row], field: &str) -> Vec<BenchLine> {
    grouped(rows)
        .into_iter()
        .map(|(series, by_n)| {
            let pts = by_n
                .into_iter()
                .map(|(n, rs)| {
                    let mut w: Vec<f64> = rs.iter().map(|r| r.wall_s).collect();
                    let mut l: Vec<f64> = rs.iter().map(|r| r.l1(field)).collect();
                    (n, median(&mut w), median(&mut l))
                })
                .filter(|p| p.1 > 0.0 && p.2 > 0.0 && p.1.is_finite() && p.2.is_finite())
                .collect();
            (series, pts)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// L1 = C N^(-2/3) is order 2 in N^(1/3).
    #[test]
    fn the_order_of_a_power_law_is_its_exponent() {
        let rows: Vec<Row> = [1000u64, 8000, 27000]
            .iter()
            .map(|&n| Row {
                case: "c".into(),
                scheme: "s".into(),
                kernel: "k".into(),
                time_steps: "global".into(),
                n,
                side: 0,
                ranks: 1,
                threads: 1,
                repeat: 0,
                steps: 1,
                particle_updates: n,
                t_end: 1.0,
                wall_s: 1.0,
                particle_steps_per_s: 1.0,
                peak_rss_bytes: 1,
                bytes_per_particle: 1.0,
                l1_rho: 3.0 * (n as f64).powf(-2.0 / 3.0),
                l1_p: 0.5 * (n as f64).powf(-1.0 / 3.0),
                l1_v: f64::NAN,
                energy_drift: 0.0,
                momentum_drift: 0.0,
                angular_momentum_drift: 0.0,
                violations: 0,
            })
            .collect();
        let o = orders(&rows);
        assert_eq!(o.len(), 2, "no order without finite L1: {o:?}");
        assert!((o[0].order - 2.0).abs() < 1e-12 && o[0].field == "l1_rho");
        assert!((o[1].order - 1.0).abs() < 1e-12 && o[1].field == "l1_p");
        assert_eq!(median(&mut [3.0, 1.0, 2.0, 10.0]), 2.5);
    }
}
