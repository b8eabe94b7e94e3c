//! PNG plots of a run's radial profile: density, pressure and speed against
//! radius, the binned particle means as markers and the reference solution as
//! a line.
//!
//! Pure Rust (plotters' bitmap backend, the `image` crate's PNG encoder, text
//! rasterised by ab_glyph from a font embedded in the binary), so it needs no
//! system library such as fontconfig or freetype.

use crate::analysis::Bin;
use crate::AppError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::error::Error;
use std::path::Path;
use std::sync::OnceLock;

/// DejaVu Sans 2.37 (Regular), subset to Basic Latin, Latin-1, Greek and a few
/// math symbols, hinting dropped (34 KB instead of 757 KB). Source: the
/// `DejaVuSans.ttf` shipped in the `dejavu` 2.37.0 crate on crates.io
/// (upstream dejavu-fonts.github.io), made with fontTools 4.68:
/// `pyftsubset DejaVuSans.ttf --unicodes="U+0020-007E,U+00A0-00FF,U+0391-03A9,
/// U+03B1-03C9,U+2013-2014,U+2022,U+2026,U+2070-209F,U+2212,U+2248,U+221E"
/// --no-hinting --legacy-kern --layout-features='kern' --drop-tables+=MATH,FFTM`.
/// Licence: the Bitstream Vera Fonts licence (permissive; DejaVu changes are
/// public domain), whose text is in `assets/DejaVuSans-LICENSE.txt`.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans-subset.ttf");

/// The family every text style below asks for.
const FAMILY: &str = "sans-serif";

/// Picture size in pixels.
const SIZE: (u32, u32) = (1200, 900);

/// Particle markers and reference line colours.
const PARTICLE_COLOR: RGBColor = RGBColor(31, 119, 180);
const REFERENCE_COLOR: RGBColor = RGBColor(214, 39, 40);

/// One panel: its axis label and how to read the particle mean and the
/// reference value from a bin.
struct Panel {
    label: &'static str,
    particles: fn(&Bin) -> f64,
    reference: fn(&Bin) -> f64,
}

const PANELS: [Panel; 3] = [
    Panel {
        label: "density ρ",
        particles: |b| b.rho,
        reference: |b| b.rho_ref,
    },
    Panel {
        label: "pressure P",
        particles: |b| b.p,
        reference: |b| b.p_ref,
    },
    Panel {
        label: "speed |v|",
        particles: |b| b.v,
        reference: |b| b.v_ref,
    },
];

/// Writes a PNG (about 1200x900 px) with three stacked panels (density, pressure, speed |v|) against radius r:
/// the binned particle means as points/markers and the reference solution as a line (skip NaN values; a bin with count 0 has NaN).
/// `title` goes on top (e.g. "sedov, 27000 particles, t = 0.0500"). Returns an error naming the path on failure.
///
/// Bins whose particle mean is NaN (no particle) get no marker; NaN
/// reference values break the line (a run without reference draws none).
pub fn profile_png(path: &Path, title: &str, bins: &[Bin]) -> Result<(), AppError> {
    render(path, title, bins).map_err(|e| AppError::io(path, std::io::Error::other(e.to_string())))
}

/// Registers the embedded font with plotters, once per process.
fn register_font() -> Result<(), Box<dyn Error>> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err("the embedded font could not be loaded".into())
    }
}

fn render(path: &Path, title: &str, bins: &[Bin]) -> Result<(), Box<dyn Error>> {
    register_font()?;
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let body = root.titled(title, (FAMILY, 28))?;
    let x_max = x_max(bins);
    for (panel, area) in PANELS.iter().zip(body.split_evenly((3, 1))) {
        draw_panel(&area, panel, bins, x_max)?;
    }
    root.present()?;
    Ok(())
}

/// The right end of the r axis: the outermost bin's outer edge.
fn x_max(bins: &[Bin]) -> f64 {
    let rs: Vec<f64> = bins.iter().map(|b| b.r).filter(|r| r.is_finite()).collect();
    let r_last = rs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if r_last <= 0.0 {
        return 1.0;
    }
    // Bin centres are (k + 1/2) dr: half a bin past the last centre.
    let half = rs.iter().copied().fold(f64::INFINITY, f64::min).max(0.0);
    r_last + half.min(0.5 * r_last)
}

/// The y range covering every finite value with 8 % margins; non-negative
/// data that come within half their maximum of 0 get an axis starting at 0.
fn y_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (min, max) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if min > max {
        return (0.0, 1.0); // no finite value
    }
    let from_zero = min >= 0.0 && min <= 0.5 * max;
    let lo = if from_zero { 0.0 } else { min };
    if max <= lo {
        // Constant data.
        return if max == 0.0 {
            (0.0, 1.0)
        } else {
            (max - 0.1 * max.abs(), max + 0.1 * max.abs())
        };
    }
    let pad = 0.08 * (max - lo);
    (if from_zero { 0.0 } else { lo - pad }, max + pad)
}

/// A tick label on an axis spanning `span` whose largest magnitude is `mag`:
/// plain decimals with as many digits as the tick spacing needs, scientific
/// notation for very large or very small magnitudes.
fn tick_label(v: f64, span: f64, mag: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    // Plotters puts at most ten ticks on an axis, 1, 2 or 5 times a power of
    // ten apart.
    let rough = span / 10.0;
    let power = 10f64.powf(rough.log10().floor());
    let step = match rough / power {
        m if m <= 1.0 => power,
        m if m <= 2.0 => 2.0 * power,
        m if m <= 5.0 => 5.0 * power,
        _ => 10.0 * power,
    };
    let step_exp = step.log10().floor();
    if (1e-3..1e5).contains(&mag) {
        let decimals = (-step_exp).clamp(0.0, 8.0) as usize;
        format!("{v:.decimals$}")
    } else {
        let decimals = (mag.log10().floor() - step_exp).clamp(0.0, 6.0) as usize;
        format!("{v:.decimals$e}")
    }
}

/// The finite `(r, value)` runs of the reference, split at NaN.
fn segments(bins: &[Bin], value: fn(&Bin) -> f64) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![];
    let mut run = vec![];
    for b in bins {
        let v = value(b);
        if b.r.is_finite() && v.is_finite() {
            run.push((b.r, v));
        } else if !run.is_empty() {
            out.push(std::mem::take(&mut run));
        }
    }
    if !run.is_empty() {
        out.push(run);
    }
    out
}

fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    panel: &Panel,
    bins: &[Bin],
    x_max: f64,
) -> Result<(), Box<dyn Error>> {
    let (y_lo, y_hi) = y_range(
        bins.iter()
            .flat_map(|b| [(panel.particles)(b), (panel.reference)(b)]),
    );
    let y_fmt = |v: &f64| tick_label(*v, y_hi - y_lo, y_lo.abs().max(y_hi.abs()));
    let x_fmt = |v: &f64| tick_label(*v, x_max, x_max);
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(90)
        .build_cartesian_2d(0.0..x_max, y_lo..y_hi)?;
    chart
        .configure_mesh()
        .x_desc("r")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_desc(panel.label)
        .label_style((FAMILY, 17))
        .axis_desc_style((FAMILY, 20))
        .max_light_lines(4)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;

    let mut labelled = false;
    for (k, run) in segments(bins, panel.reference).into_iter().enumerate() {
        let series = chart.draw_series(LineSeries::new(run, REFERENCE_COLOR.stroke_width(2)))?;
        if k == 0 {
            series.label("reference").legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], REFERENCE_COLOR.stroke_width(2))
            });
            labelled = true;
        }
    }
    let points: Vec<(f64, f64)> = bins
        .iter()
        .map(|b| (b.r, (panel.particles)(b)))
        .filter(|(r, v)| r.is_finite() && v.is_finite())
        .collect();
    if !points.is_empty() {
        chart
            .draw_series(
                points
                    .into_iter()
                    .map(|xy| Circle::new(xy, 3, PARTICLE_COLOR.filled())),
            )?
            .label("particles")
            .legend(|(x, y)| Circle::new((x + 12, y), 4, PARTICLE_COLOR.filled()));
        labelled = true;
    }
    if labelled {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FAMILY, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

/// One energy series of [`energy_png`]: name, colour and (t, E) samples.
pub type EnergySeries<'a> = (&'a str, RGBColor, &'a [(f64, f64)]);

/// Writes a PNG of energies against time: each series as a line, the
/// reference values as large hollow markers of the series' colour.
pub fn energy_png(
    path: &Path,
    title: &str,
    series: &[EnergySeries<'_>],
    reference: &[EnergySeries<'_>],
) -> Result<(), AppError> {
    series_png(path, title, "energy", series, reference)
}

/// Writes a PNG of quantities against time, as [`energy_png`] does, with
/// `y_label` on the vertical axis.
pub fn series_png(
    path: &Path,
    title: &str,
    y_label: &str,
    series: &[EnergySeries<'_>],
    reference: &[EnergySeries<'_>],
) -> Result<(), AppError> {
    render_series(path, title, y_label, series, reference)
        .map_err(|e| AppError::io(path, std::io::Error::other(e.to_string())))
}

fn render_series(
    path: &Path,
    title: &str,
    y_label: &str,
    series: &[EnergySeries<'_>],
    reference: &[EnergySeries<'_>],
) -> Result<(), Box<dyn Error>> {
    register_font()?;
    let all = || series.iter().chain(reference).flat_map(|s| s.2.iter());
    let t_max = all().map(|p| p.0).fold(0.0, f64::max).max(1e-12);
    let (y_lo, y_hi) = y_range(all().map(|p| p.1));
    let root = BitMapBackend::new(path, (1200, 700)).into_drawing_area();
    root.fill(&WHITE)?;
    let body = root.titled(title, (FAMILY, 28))?;
    let y_fmt = |v: &f64| tick_label(*v, y_hi - y_lo, y_lo.abs().max(y_hi.abs()));
    let x_fmt = |v: &f64| tick_label(*v, t_max, t_max);
    let mut chart = ChartBuilder::on(&body)
        .margin(8)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(90)
        .build_cartesian_2d(0.0..t_max, y_lo..y_hi)?;
    chart
        .configure_mesh()
        .x_desc("t")
        .y_desc(y_label)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FAMILY, 17))
        .axis_desc_style((FAMILY, 20))
        .max_light_lines(4)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for &(name, colour, points) in series {
        chart
            .draw_series(LineSeries::new(
                points.iter().copied().filter(|p| p.1.is_finite()),
                colour.stroke_width(2),
            ))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2))
            });
    }
    for &(name, colour, points) in reference {
        chart
            .draw_series(
                points
                    .iter()
                    .map(|&xy| Circle::new(xy, 7, colour.stroke_width(2))),
            )?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 12, y), 6, colour.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .label_font((FAMILY, 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// Line colours of the benchmark series, in turn.
const SERIES_COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Colours of the reference series (none of them one of ours).
const REFERENCE_COLORS: [RGBColor; 3] = [
    RGBColor(0, 0, 0),
    RGBColor(188, 189, 34),
    RGBColor(127, 127, 127),
];

/// One line of an error-against-time panel: its legend label and its
/// points `(N, wall time, L1)`.
pub type BenchLine = (String, Vec<(u64, f64, f64)>);

/// One panel of [`bench_png`]: the axis label of its L1 field, the lines
/// of our runs and those of a reference code.
#[derive(Debug, Clone)]
pub struct BenchPanel {
    /// The y axis label.
    pub label: &'static str,
    /// Our runs' lines (solid, filled points).
    pub runs: Vec<BenchLine>,
    /// Another code's lines (thin, hollow squares, colours of their own).
    pub reference: Vec<BenchLine>,
}

/// Writes `error_vs_time.png`: the `panels` side by side, L1 against wall
/// time on log-log axes, each point labelled with the side N^(1/3); the
/// legend sits above the lines.
pub fn bench_png(path: &Path, title: &str, panels: &[BenchPanel]) -> Result<(), AppError> {
    render_bench(path, title, panels)
        .map_err(|e| AppError::io(path, std::io::Error::other(e.to_string())))
}

/// A tick label of a log axis: three significant digits, no trailing
/// zeros.
fn log_tick(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.log10().floor() as i32).clamp(0, 8) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Ticks of a log axis from `lo` to `hi`: 1, 2 and 5 times the powers of
/// ten (and 3 when the axis spans less than a decade and a half).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mantissas: &[f64] = if hi / lo < 30.0 {
        &[1.0, 1.5, 2.0, 3.0, 5.0, 7.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in mantissas {
            let v = m * decade;
            if v >= lo && v <= hi {
                ticks.push(v);
            }
        }
        decade *= 10.0;
    }
    ticks
}

/// A log axis range around `values` (a factor 1.25 on each side).
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if lo > hi {
        return (0.1, 10.0);
    }
    (lo / 1.25, hi * 1.25)
}

fn render_bench(path: &Path, title: &str, panels: &[BenchPanel]) -> Result<(), Box<dyn Error>> {
    register_font()?;
    let n = panels.len().max(1);
    let root = BitMapBackend::new(path, (600 * n as u32, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let body = root.titled(title, (FAMILY, 26))?;
    let points = |p: &BenchPanel| {
        let lines: Vec<(u64, f64, f64)> = p
            .runs
            .iter()
            .chain(&p.reference)
            .flat_map(|l| l.1.clone())
            .collect();
        lines
    };
    let (x_lo, x_hi) = log_range(panels.iter().flat_map(points).map(|p| p.1));
    // The legend gets the top of each panel to itself: the y range grows
    // upwards by its share of the height (about 21 px a line of ~540).
    let entries = panels
        .first()
        .map_or(0, |p| p.runs.len() + p.reference.len());
    let legend_share = ((entries as f64 * 21.0 + 16.0) / 540.0).min(0.5);
    // Each point's label: the side N^(1/3) of its particle count.
    let side_labels = |pts: &[(u64, f64, f64)], colour: RGBColor| {
        pts.iter()
            .map(move |p| {
                EmptyElement::at((p.1, p.2))
                    + Text::new(
                        format!("{}³", (p.0 as f64).cbrt().round()),
                        (7, -18),
                        (FAMILY, 14).into_font().color(&colour),
                    )
            })
            .collect::<Vec<_>>()
    };
    for (panel, area) in panels.iter().zip(body.split_evenly((1, n))) {
        let (y_lo, y_hi) = log_range(points(panel).into_iter().map(|p| p.2));
        let y_hi = y_hi * (y_hi / y_lo).powf(legend_share / (1.0 - legend_share));
        let mut chart = ChartBuilder::on(&area)
            .margin(8)
            .margin_right(16)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (x_lo..x_hi)
                    .log_scale()
                    .with_key_points(log_ticks(x_lo, x_hi)),
                (y_lo..y_hi)
                    .log_scale()
                    .with_key_points(log_ticks(y_lo, y_hi)),
            )?;
        chart
            .configure_mesh()
            .x_desc("wall time (s)")
            .y_desc(panel.label)
            .x_label_formatter(&|v| log_tick(*v))
            .y_label_formatter(&|v| log_tick(*v))
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 18))
            .max_light_lines(1)
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        let mut any = false;
        for (k, (legend, pts)) in panel.runs.iter().enumerate() {
            if pts.is_empty() {
                continue;
            }
            any = true;
            let colour = SERIES_COLORS[k % SERIES_COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.1, p.2)),
                    colour.stroke_width(2),
                ))?
                .label(legend)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(2))
                });
            chart.draw_series(
                pts.iter()
                    .map(|p| Circle::new((p.1, p.2), 4, colour.filled())),
            )?;
            chart.draw_series(side_labels(pts, colour))?;
        }
        for (k, (legend, pts)) in panel.reference.iter().enumerate() {
            if pts.is_empty() {
                continue;
            }
            any = true;
            let colour = REFERENCE_COLORS[k % REFERENCE_COLORS.len()];
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.1, p.2)),
                    colour.stroke_width(1),
                ))?
                .label(format!("{legend} (reference)"))
                .legend(move |(x, y)| Rectangle::new([(x + 7, y - 5), (x + 17, y + 5)], colour));
            chart.draw_series(pts.iter().map(|p| {
                let (x, y) = (p.1, p.2);
                EmptyElement::at((x, y))
                    + Rectangle::new([(-5, -5), (5, 5)], colour.stroke_width(2))
            }))?;
            chart.draw_series(side_labels(pts, colour))?;
        }
        if any {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .label_font((FAMILY, 14))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

/// One spectrum of [`spectra_png`]: its time and `(k, E(k))` points.
pub type SpectrumLine = (f64, Vec<(f64, f64)>);

/// Writes `spectrum.png`: E(k) against k on log-log axes, one line per
/// time in `lines` (earlier ones fainter, the last bold), with a `k^-2`
/// guide (Burgers) through the last line's value at k = 2.
pub fn spectra_png(path: &Path, title: &str, lines: &[SpectrumLine]) -> Result<(), AppError> {
    render_spectra(path, title, lines)
        .map_err(|e| AppError::io(path, std::io::Error::other(e.to_string())))
}

fn render_spectra(path: &Path, title: &str, lines: &[SpectrumLine]) -> Result<(), Box<dyn Error>> {
    register_font()?;
    let positive = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
        pts.iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.1.is_finite())
            .collect()
    };
    let all: Vec<(f64, f64)> = lines.iter().flat_map(|l| positive(&l.1)).collect();
    let (x_lo, x_hi) = log_range(all.iter().map(|p| p.0));
    let (y_lo, y_hi) = log_range(all.iter().map(|p| p.1));
    let root = BitMapBackend::new(path, (1000, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let body = root.titled(title, (FAMILY, 26))?;
    let mut chart = ChartBuilder::on(&body)
        .margin(8)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(90)
        .build_cartesian_2d(
            (x_lo..x_hi)
                .log_scale()
                .with_key_points(log_ticks(x_lo, x_hi)),
            (y_lo..y_hi)
                .log_scale()
                .with_key_points(log_ticks(y_lo, y_hi)),
        )?;
    chart
        .configure_mesh()
        .x_desc("k L / 2π")
        .y_desc("E(k)")
        .x_label_formatter(&|v| log_tick(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FAMILY, 17))
        .axis_desc_style((FAMILY, 20))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    let n = lines.len();
    for (i, (t, pts)) in lines.iter().enumerate() {
        let last = i + 1 == n;
        let shade = if last {
            1.0
        } else {
            0.15 + 0.5 * i as f64 / n.max(1) as f64
        };
        let style = PARTICLE_COLOR
            .mix(shade)
            .stroke_width(if last { 3 } else { 1 });
        let series = chart.draw_series(LineSeries::new(positive(pts), style))?;
        if last {
            series
                .label(format!("t = {t:.3}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        }
    }
    if let Some((_, pts)) = lines.last() {
        if let Some(&(_, e2)) = pts.iter().find(|p| p.0 == 2.0) {
            let guide = move |k: f64| e2 * (k / 2.0).powi(-2);
            let style = REFERENCE_COLOR.stroke_width(2);
            chart
                .draw_series(LineSeries::new(
                    [x_lo.max(1.0), x_hi].map(|k| (k, guide(k))),
                    style,
                ))?
                .label("k^-2")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sedov-like synthetic bins: a shell peaking at r = 0.3, an empty
    /// innermost bin and a bin without reference value.
    fn bins() -> Vec<Bin> {
        let n = 40;
        let dr = 0.5 / n as f64;
        (0..n)
            .map(|k| {
                let r = (k as f64 + 0.5) * dr;
                let x = r / 0.3;
                let (rho_ref, p_ref, v_ref) = if x < 1.0 {
                    (4.0 * x.powi(6), 0.3 + 2.0 * x.powi(8), 1.2 * x)
                } else {
                    (1.0, 0.0, 0.0)
                };
                let wiggle = 0.9 + 0.2 * ((k * 7 % 5) as f64 / 4.0);
                let empty = k == 0;
                let nan = f64::NAN;
                Bin {
                    r,
                    count: if empty { 0 } else { 10 * k },
                    rho: if empty {
                        nan
                    } else {
                        rho_ref.max(0.05) * wiggle
                    },
                    p: if empty { nan } else { p_ref * wiggle },
                    v: if empty { nan } else { v_ref * wiggle },
                    rho_ref: if k == 20 { nan } else { rho_ref },
                    p_ref,
                    v_ref,
                }
            })
            .collect()
    }

    fn temp_png(tag: &str) -> std::path::PathBuf {
        crate::test_dir(&format!("plot-{tag}")).join("plot.png")
    }

    #[test]
    fn plot_writes_a_png() {
        let path = temp_png("profile");
        profile_png(&path, "sedov, 64000 particles, t = 0.0500", &bins()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(bytes.len() > 8 * 1024, "only {} bytes", bytes.len());
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }

    #[test]
    fn plot_without_reference_or_particles() {
        let mut no_ref = bins();
        for b in &mut no_ref {
            (b.rho_ref, b.p_ref, b.v_ref) = (f64::NAN, f64::NAN, f64::NAN);
        }
        let empty: Vec<Bin> = no_ref
            .iter()
            .map(|b| Bin {
                count: 0,
                rho: f64::NAN,
                p: f64::NAN,
                v: f64::NAN,
                ..*b
            })
            .collect();
        for (tag, bins) in [("noref", no_ref), ("empty", empty), ("none", vec![])] {
            let path = temp_png(tag);
            profile_png(&path, tag, &bins).unwrap();
            assert!(std::fs::metadata(&path).unwrap().len() > 1024);
            std::fs::remove_file(&path).unwrap();
        }
    }

    #[test]
    fn plot_axis_ranges_and_tick_labels() {
        assert_eq!(y_range([0.2, 4.0, f64::NAN].into_iter()), (0.0, 4.32));
        let (lo, hi) = y_range([1000.0, 1004.0].into_iter());
        assert!((lo - 999.68).abs() < 1e-9 && (hi - 1004.32).abs() < 1e-9);
        assert_eq!(y_range([f64::NAN].into_iter()), (0.0, 1.0));
        assert_eq!(y_range([0.0, 0.0].into_iter()), (0.0, 1.0));
        assert_eq!(tick_label(0.5, 3.9, 3.9), "0.5");
        assert_eq!(tick_label(0.0, 3.9, 3.9), "0");
        assert_eq!(tick_label(1.5e6, 2.6e6, 2.6e6), "1.5e6");
        assert_eq!(tick_label(4e-6, 1.5e-5, 1.5e-5), "4.0e-6");
    }

    #[test]
    fn plot_error_names_the_path() {
        let path = temp_png("missing-dir").join("profile.png");
        let err = profile_png(&path, "t", &bins()).unwrap_err();
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
    }
}
