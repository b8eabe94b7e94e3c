//! Glass initial conditions: a periodic block of equal-mass particles with
//! no lattice directions and nearly uniform SPH density, made by relaxing
//! random positions with the solver's own kernel and neighbour count.
//!
//! [`relax`] places `side^3` particles at random in the periodic unit cube
//! (an ideal gas at uniform `u`, so pressure follows density) and lets the
//! pressure gradients push them apart, overdamped: after every step of the
//! solver each particle is moved by [`KAPPA`]` h^2 a / c^2` down the
//! pressure gradient instead of the solver's move (never more than
//! [`MAX_SHIFT`] of its `h`), its velocity and the integrator's history are
//! cleared, and the heat the viscosity made is taken out again. It stops when the density scatter
//! `std(rho) / mean(rho)` falls below the tolerance or at the step limit.
//!
//! [`cached`] keeps every glass in a folder under a name made of
//! `(side, kernel, ng0, ngmax)` and [`RELAXATION_VERSION`], checksummed
//! (`sph-io`), so a glass is relaxed once and reused, and a glass of an
//! older relaxation is never taken for one of the current.
//! [`Glass::fill`] tiles a box with copies of a block scaled to a given
//! mean spacing.
//!
//! ```
//! use sph_apps::glass::{relax, GlassSpec};
//!
//! let spec = GlassSpec { side: 8, ..GlassSpec::default() };
//! let glass = relax(&spec, 400, 0.02, |_| {})?;
//! assert_eq!(glass.pos.len(), 512);
//! // Random positions scatter the density by tens of percent; the glass
//! // by about one.
//! assert!(glass.report.rho_scatter < 0.25 * glass.report.rho_scatter_start);
//! // Copies of the block fill a box at spacing 0.1.
//! let filled = glass.fill([0.0; 3], [1.6, 0.8, 0.8], 0.1);
//! assert_eq!(filled.len(), 16 * 8 * 8);
//! # Ok::<(), sph_apps::AppError>(())
//! ```

use crate::cases::scheme::{Physics, SchemeOverrides};
use crate::cases::setup::{initial_h, Share};
use crate::rng::SplitMix64;
use crate::AppError;
use serde::Serialize;
use sph_core::{Gradients, Hydro, HydroConfig, Particles, Scheme};
use sph_io::{
    Attr, BoxSpec, FieldData, H5Part, Selection, Snapshot, SnapshotReader, SnapshotWriter,
};
use sph_kernels::{FastKernel, KernelChoice};
use sph_tree::{Boundary, BoundingBox};
use std::path::{Path, PathBuf};

/// Largest move of one relaxation step, in units of the particle's `h`:
/// a particle that random placement put on top of another is pushed hard,
/// and must not jump across its neighbourhood.
pub const MAX_SHIFT: f64 = 0.2;

/// Relaxation step: each particle moves by `KAPPA h^2 a / c^2` (the
/// solver's own move, about `a dt^2 = 0.04 h^2 a / c^2` at Courant 0.2,
/// takes 6x more steps). Measured on 16^3 with sinc:6 and ng0 = 100,
/// steps to a density scatter of 0.01: 0.1 about 60, 0.2 41, 0.4 never
/// (the moves overshoot and oscillate).
pub const KAPPA: f64 = 0.2;

/// Version of the relaxation: part of a cached glass's file name and
/// attributes, and [`read`] refuses a glass of another version, so a change
/// to the relaxation never reuses a glass made by the old one. Bump it with
/// every change that moves a relaxed particle by one bit (this module, the
/// solver steps it runs, the kernels); the unit test
/// `relaxed_glass_matches_its_version` records the positions' checksum per
/// version and fails until it is bumped.
pub const RELAXATION_VERSION: u32 = 1;

/// What a glass is made for: its particle count and the kernel and
/// neighbour counts of the runs that use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlassSpec {
    /// Particles per side (`side^3` in the block).
    pub side: usize,
    /// Kernel.
    pub kernel: KernelChoice,
    /// Target neighbour count.
    pub ng0: usize,
    /// Most neighbours.
    pub ngmax: usize,
}

impl Default for GlassSpec {
    /// 16^3 particles for the default kernel and neighbour counts.
    fn default() -> Self {
        let n = HydroConfig::default().neighbors;
        GlassSpec {
            side: 16,
            kernel: KernelChoice::default(),
            ng0: n.ng0,
            ngmax: n.ngmax,
        }
    }
}

impl GlassSpec {
    /// The cache file's name, e.g. `glass_16_sinc6_ng100_150_v1.h5` (the
    /// last part is [`RELAXATION_VERSION`]); a decimal point in the
    /// kernel's exponent becomes `p` (`sinc:6.5` is `sinc6p5`, not the
    /// `sinc65` of `sinc:65`).
    pub fn file_name(&self) -> String {
        let kernel: String = self
            .kernel
            .to_string()
            .chars()
            .filter_map(|c| match c {
                '.' => Some('p'),
                c if c.is_ascii_alphanumeric() => Some(c),
                _ => None,
            })
            .collect();
        format!(
            "glass_{}_{kernel}_ng{}_{}_v{RELAXATION_VERSION}.h5",
            self.side, self.ng0, self.ngmax
        )
    }

    fn check(&self) -> Result<(), AppError> {
        if !(MIN_SIDE..=MAX_SIDE).contains(&self.side) {
            return Err(AppError::Usage(format!(
                "glass: {} particles per side; allowed {MIN_SIDE} to {MAX_SIDE}",
                self.side
            )));
        }
        if self.ng0 < 8 || self.ng0 > self.ngmax {
            return Err(AppError::Usage(format!(
                "glass: ng0 {} must be at least 8 and at most ngmax {}",
                self.ng0, self.ngmax
            )));
        }
        Ok(())
    }
}

/// How a relaxation went.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Relaxation {
    /// Solver steps taken.
    pub steps: u64,
    /// `std(rho) / mean(rho)` of the random start.
    pub rho_scatter_start: f64,
    /// The same at the end.
    pub rho_scatter: f64,
    /// Closest pair of the random start, in units of the mean spacing.
    pub min_pair_start: f64,
    /// The same at the end.
    pub min_pair: f64,
}

/// One relaxation step's figures, for progress reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxStep {
    /// Step number.
    pub step: u64,
    /// Largest move of the step, in units of the mean spacing.
    pub max_shift: f64,
}

/// A glass block: positions in the periodic unit cube `[0, 1)^3`.
#[derive(Debug, Clone, PartialEq)]
pub struct Glass {
    /// What it was made for.
    pub spec: GlassSpec,
    /// Positions, `side^3` of them.
    pub pos: Vec<[f64; 3]>,
    /// How its relaxation went.
    pub report: Relaxation,
}

impl Glass {
    /// Copies of the block, each scaled to `side * spacing` per edge,
    /// tiled from `lo` over the box `[lo, hi)`: the points inside it, in
    /// tile order (x fastest). The mean spacing is `spacing`; a box whose
    /// edges are whole multiples of the tile has no seam across its
    /// periodic boundaries.
    pub fn fill(&self, lo: [f64; 3], hi: [f64; 3], spacing: f64) -> Vec<[f64; 3]> {
        let tile = self.spec.side as f64 * spacing;
        let tiles = [0, 1, 2].map(|k| (((hi[k] - lo[k]) / tile) - 1e-9).ceil().max(0.0) as usize);
        let mut out = Vec::new();
        for t in 0..tiles[0] * tiles[1] * tiles[2] {
            let c = [
                t % tiles[0],
                t / tiles[0] % tiles[1],
                t / (tiles[0] * tiles[1]),
            ];
            for q in &self.pos {
                let x = [0, 1, 2].map(|k| lo[k] + (c[k] as f64 + q[k]) * tile);
                if (0..3).all(|k| x[k] < hi[k]) {
                    out.push(x);
                }
            }
        }
        out
    }
}

/// The cache folder: `$SPHEXA_GLASS_DIR`, else
/// `$XDG_CACHE_HOME/sphexa/glass`, else `$HOME/.cache/sphexa/glass`, else
/// `glass/` under the working directory (where the user sees it; a shared
/// folder such as `/tmp` could hold another user's files; the repository
/// ignores `/glass/`).
pub fn default_cache_dir() -> PathBuf {
    let var = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("SPHEXA_GLASS_DIR")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("sphexa").join("glass")))
        .or_else(|| var("HOME").map(|d| d.join(".cache").join("sphexa").join("glass")))
        .unwrap_or_else(|| PathBuf::from("glass"))
}

/// Relaxes `spec.side^3` random particles in the periodic unit cube until
/// the density scatter is below `tolerance` or `max_steps` have run;
/// `progress` sees every step.
///
/// # Errors
/// A spec out of range, or a failure of the solver.
pub fn relax(
    spec: &GlassSpec,
    max_steps: u64,
    tolerance: f64,
    mut progress: impl FnMut(RelaxStep),
) -> Result<Glass, AppError> {
    relax_reporting_to(spec, max_steps, tolerance, &mut progress)
}

/// [`relax`] with the observer behind a pointer: this body (and the solver
/// it drives) is compiled once, here, instead of once more in every crate
/// that passes its own closure (optimised builds share no generic code
/// between crates).
fn relax_reporting_to(
    spec: &GlassSpec,
    max_steps: u64,
    tolerance: f64,
    progress: &mut dyn FnMut(RelaxStep),
) -> Result<Glass, AppError> {
    spec.check()?;
    let n = spec.side.pow(3);
    let spacing = 1.0 / spec.side as f64;
    let mut config = HydroConfig::default();
    config.neighbors.ng0 = spec.ng0;
    config.neighbors.ngmax = spec.ngmax;
    // Kernel gradients: the cheapest operator; the gas is at rest, so the
    // viscosity has nothing to do.
    let mut scheme = Scheme::PAPER;
    scheme.gradients = Gradients::Kernel;
    scheme.grad_h = false;
    SchemeOverrides::default().apply(scheme, Physics::IDEAL_GAS, &mut config);
    let (mut p, _) = Share::WHOLE.particles(n, config.fields());
    let mut rng = SplitMix64(0x5EED ^ n as u64);
    let h0 = initial_h(spec.ng0, 1.0, n);
    const U: f64 = 1.0;
    for i in 0..n {
        (p.x[i], p.y[i], p.z[i]) = (rng.uniform(), rng.uniform(), rng.uniform());
        p.m[i] = 1.0 / n as f64;
        p.h[i] = h0;
        p.u[i] = U;
    }
    let mut bbox = BoundingBox::new([0.0; 3], [1.0; 3], [Boundary::Periodic; 3])?;
    let kernel: FastKernel = spec.kernel.fast()?;
    // The gas's sound speed at the mean density (the same everywhere at rho 1).
    let (_, sound) = Physics::IDEAL_GAS.eos.pressure_sound(1.0, U);
    let mut hydro = Hydro::new(kernel, config, 0.0, 0.2 * h0 / sound)?;
    hydro.prepare(&mut p);

    let min_pair_start = closest_pair(&p, 0..n, spec.side) / spacing;
    hydro.evaluate_density(&mut p, &mut bbox)?;
    let rho_scatter_start = scatter(&p.rho[hydro.owned()]);
    let mut rho_scatter = rho_scatter_start;
    let mut steps = 0;
    while steps < max_steps && rho_scatter > tolerance {
        hydro.step(&mut p, &mut bbox)?;
        steps += 1;
        let owned = hydro.owned();
        let mut max_shift: f64 = 0.0;
        for i in owned.clone() {
            // Undo the solver's move; move by kappa h^2 a / c^2 instead.
            let k = KAPPA * p.h[i] * p.h[i] / (sound * sound);
            let mut d = [k * p.ax[i], k * p.ay[i], k * p.az[i]];
            let len = d.iter().map(|c| c * c).sum::<f64>().sqrt();
            let cap = MAX_SHIFT * p.h[i];
            if len > cap {
                d = d.map(|c| c * cap / len);
            }
            let x = bbox.wrap([
                p.x[i] - p.dx[i] + d[0],
                p.y[i] - p.dy[i] + d[1],
                p.z[i] - p.dz[i] + d[2],
            ]);
            (p.x[i], p.y[i], p.z[i]) = (x[0], x[1], x[2]);
            max_shift = max_shift.max(len.min(cap));
        }
        // Overdamped: no momentum, no heat carried into the next step.
        for c in [
            &mut p.vx, &mut p.vy, &mut p.vz, &mut p.dx, &mut p.dy, &mut p.dz,
        ] {
            c.fill(0.0);
        }
        p.u.fill(U);
        p.du_prev.fill(0.0);
        // The step's density is that of the positions before its move.
        rho_scatter = scatter(&p.rho[owned]);
        progress(RelaxStep {
            step: steps,
            max_shift: max_shift / spacing,
        });
    }
    hydro.evaluate_density(&mut p, &mut bbox)?;
    let owned = hydro.owned();
    rho_scatter = scatter(&p.rho[owned.clone()]);
    let min_pair = closest_pair(&p, owned.clone(), spec.side) / spacing;
    let pos = owned.map(|i| [p.x[i], p.y[i], p.z[i]]).collect();
    Ok(Glass {
        spec: *spec,
        pos,
        report: Relaxation {
            steps,
            rho_scatter_start,
            rho_scatter,
            min_pair_start,
            min_pair,
        },
    })
}

/// The glass of `spec` from `dir` if it is there and reads back as one
/// (checksums, spec), else relaxed (to a density scatter of
/// [`TOLERANCE`], at most [`MAX_STEPS`] steps) and stored there, replacing
/// a damaged or foreign file of that name.
///
/// # Errors
/// A spec out of range, a failed relaxation, or a cache folder that
/// cannot be written.
pub fn cached(spec: &GlassSpec, dir: &Path) -> Result<Glass, AppError> {
    spec.check()?;
    let path = dir.join(spec.file_name());
    if let Ok(glass) = read(&path, spec) {
        return Ok(glass);
    }
    let glass = relax(spec, MAX_STEPS, TOLERANCE, |_| {})?;
    std::fs::create_dir_all(dir).map_err(|e| AppError::io(dir, e))?;
    // Under a name of this writer first: the ranks of a distributed run,
    // or threads of one process, may relax the same glass (bit-identical)
    // and store it at once.
    static WRITERS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let k = WRITERS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mine = dir.join(format!("{}.{}-{k}", spec.file_name(), std::process::id()));
    write(&glass, &mine)?;
    std::fs::rename(&mine, &path).map_err(|e| AppError::io(&path, e))?;
    Ok(glass)
}

/// Fewest particles per side of a glass block: below 6 the kernel's
/// support (about 2.9 spacings at ng0 = 100) reaches over half the block,
/// and a particle would meet its own periodic image.
pub const MIN_SIDE: usize = 6;
/// Most particles per side of a glass block.
pub const MAX_SIDE: usize = 200;

/// Density scatter at which [`cached`] stops relaxing.
pub const TOLERANCE: f64 = 0.005;
/// Most steps [`cached`] relaxes.
pub const MAX_STEPS: u64 = 1000;

/// Writes `glass` as one H5Part step (`x`, `y`, `z`; the spec, the
/// relaxation's figures and [`RELAXATION_VERSION`] as attributes).
///
/// # Errors
/// The file cannot be written.
pub fn write(glass: &Glass, path: &Path) -> Result<(), AppError> {
    write_version(glass, path, RELAXATION_VERSION)
}

/// [`write()`] with the relaxation version `version`.
fn write_version(glass: &Glass, path: &Path, version: u32) -> Result<(), AppError> {
    let bbox = BoxSpec {
        lo: [0.0; 3],
        hi: [1.0; 3],
        periodic: [true; 3],
    };
    let mut s = Snapshot::new(glass.report.steps, 0.0, 0.0, bbox);
    let r = glass.report;
    s.set_attr("glass_side", Attr::I64(glass.spec.side as i64))
        .set_attr("kernel", Attr::Str(glass.spec.kernel.to_string()))
        .set_attr("ng0", Attr::I64(glass.spec.ng0 as i64))
        .set_attr("ngmax", Attr::I64(glass.spec.ngmax as i64))
        .set_attr("rho_scatter_start", Attr::F64(r.rho_scatter_start))
        .set_attr("rho_scatter", Attr::F64(r.rho_scatter))
        .set_attr("min_pair_start", Attr::F64(r.min_pair_start))
        .set_attr("min_pair", Attr::F64(r.min_pair))
        .set_attr("relaxation_version", Attr::I64(i64::from(version)));
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        s.set_field(
            name,
            FieldData::F64(glass.pos.iter().map(|q| q[k]).collect()),
        );
    }
    H5Part.write(path, &s, &Selection::All)?;
    Ok(())
}

/// Reads a glass written by [`write()`], checking that it is one of `spec`
/// made by this [`RELAXATION_VERSION`].
///
/// # Errors
/// An unreadable or corrupted file, or a glass of another spec or
/// relaxation version.
pub fn read(path: &Path, spec: &GlassSpec) -> Result<Glass, AppError> {
    let s = H5Part.read_step(path, 0, &Selection::All)?;
    let bad = |what: &str| {
        AppError::Usage(format!(
            "{}: {what}; not the glass for {} particles per side, kernel {}, ng0 {}, ngmax {} (delete it to make a new one)",
            path.display(),
            spec.side,
            spec.kernel,
            spec.ng0,
            spec.ngmax
        ))
    };
    let whole = |k: &str| match s.attr(k) {
        Some(Attr::I64(v)) if *v >= 0 => Ok(*v as usize),
        _ => Err(bad(&format!("no attribute {k}"))),
    };
    let real = |k: &str| match s.attr(k) {
        Some(Attr::F64(v)) => Ok(*v),
        _ => Err(bad(&format!("no attribute {k}"))),
    };
    let version = match s.attr("relaxation_version") {
        Some(Attr::I64(v)) => Some(*v),
        _ => None,
    };
    if version != Some(i64::from(RELAXATION_VERSION)) {
        return Err(bad(&format!(
            "relaxation version {}, this build relaxes version {RELAXATION_VERSION}",
            version.map_or("none".to_string(), |v| v.to_string())
        )));
    }
    let kernel = match s.attr("kernel") {
        Some(Attr::Str(k)) => k.clone(),
        _ => return Err(bad("no attribute kernel")),
    };
    if whole("glass_side")? != spec.side
        || whole("ng0")? != spec.ng0
        || whole("ngmax")? != spec.ngmax
        || kernel != spec.kernel.to_string()
    {
        return Err(bad("its attributes differ"));
    }
    let coord = |k: &str| {
        s.field(k)
            .and_then(FieldData::as_f64)
            .ok_or_else(|| bad(&format!("no f64 field {k}")))
    };
    let (x, y, z) = (coord("x")?, coord("y")?, coord("z")?);
    if x.len() != spec.side.pow(3) {
        return Err(bad(&format!("{} particles", x.len())));
    }
    let inside = |v: f64| (0.0..1.0).contains(&v);
    if !x.iter().chain(y).chain(z).all(|&v| inside(v)) {
        return Err(bad("a position outside [0, 1)"));
    }
    Ok(Glass {
        spec: *spec,
        pos: (0..x.len()).map(|i| [x[i], y[i], z[i]]).collect(),
        report: Relaxation {
            steps: s.step,
            rho_scatter_start: real("rho_scatter_start")?,
            rho_scatter: real("rho_scatter")?,
            min_pair_start: real("min_pair_start")?,
            min_pair: real("min_pair")?,
        },
    })
}

/// `std(v) / mean(v)`.
fn scatter(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    var.sqrt() / mean
}

/// The closest pair among `range` of `p` in the periodic unit cube, by
/// cells of about one mean spacing (`side` per edge).
fn closest_pair(p: &Particles, range: std::ops::Range<usize>, side: usize) -> f64 {
    let cells = side.max(3);
    let cell_of = |v: f64| ((v * cells as f64) as usize).min(cells - 1);
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); cells * cells * cells];
    let index = |c: [usize; 3]| c[0] + cells * (c[1] + cells * c[2]);
    for i in range.clone() {
        grid[index([cell_of(p.x[i]), cell_of(p.y[i]), cell_of(p.z[i])])].push(i);
    }
    let wrap = |d: f64| d - d.round();
    let mut best = f64::INFINITY;
    // A pair closer than one cell edge lies in adjacent cells; farther
    // pairs do not matter once any pair below one edge is found, and a
    // block always has one (the mean spacing is one edge).
    for i in range {
        let c = [cell_of(p.x[i]), cell_of(p.y[i]), cell_of(p.z[i])];
        for o in 0..27 {
            let nb = [o % 3, o / 3 % 3, o / 9].map(|k| k as isize - 1);
            let cn = [0, 1, 2].map(|k| (c[k] as isize + nb[k]).rem_euclid(cells as isize) as usize);
            for &j in &grid[index(cn)] {
                if j <= i {
                    continue;
                }
                let d = [
                    wrap(p.x[i] - p.x[j]),
                    wrap(p.y[i] - p.y[j]),
                    wrap(p.z[i] - p.z[j]),
                ];
                best = best.min(d.iter().map(|c| c * c).sum::<f64>());
            }
        }
    }
    best.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FNV-1a (64 bits) of `bytes` from `h`: a stable hash (std's
    /// `DefaultHasher` may change between Rust versions).
    fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        h
    }

    const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

    /// The positions' bits, in order.
    fn checksum(pos: &[[f64; 3]]) -> u64 {
        pos.iter()
            .flatten()
            .fold(FNV_OFFSET, |h, v| fnv1a(h, &v.to_bits().to_le_bytes()))
    }

    /// Steps of the checked relaxation.
    const CHECK_STEPS: u64 = 40;

    /// `(RELAXATION_VERSION, built with FMA, checksum)` of the 8^3 glass
    /// after [`CHECK_STEPS`] steps. A build that targets FMA fuses the
    /// kernels' multiply-adds (`sph_kernels::lanes::mul_add`), which
    /// changes the last bits, so each version has one checksum per setting
    /// (`RUSTFLAGS="-C target-cpu=x86-64"` builds without FMA).
    const RELAXED_CHECKSUMS: &[(u32, bool, u64)] = &[
        (1, true, 0x97d5_b849_8e5a_fce2),
        (1, false, 0xac77_5240_d680_0129),
    ];

    /// Guards [`RELAXATION_VERSION`]: relaxes 8^3 particles for
    /// [`CHECK_STEPS`] steps (tolerance 0, so always that many) and compares
    /// the checksum of the positions with the one recorded for this version
    /// and FMA setting; a change to the relaxation fails here until the
    /// version is bumped and the new checksums are recorded.
    #[test]
    fn relaxed_glass_matches_its_version() {
        assert_eq!(fnv1a(FNV_OFFSET, b"a"), 0xaf63_dc4c_8601_ec8c, "FNV-1a");
        let spec = GlassSpec {
            side: 8,
            ..GlassSpec::default()
        };
        let g = relax(&spec, CHECK_STEPS, 0.0, |_| {}).expect("relaxes");
        assert_eq!(g.report.steps, CHECK_STEPS);
        let got = checksum(&g.pos);
        let fma = cfg!(target_feature = "fma");
        let recorded = RELAXED_CHECKSUMS
            .iter()
            .find(|&&(v, f, _)| v == RELAXATION_VERSION && f == fma)
            .map(|&(_, _, c)| c);
        let shown = recorded.map_or("none".to_string(), |c| format!("{c:#018x}"));
        assert!(
            recorded == Some(got),
            "the relaxed 8^3 glass has checksum {got:#018x} (FMA {fma}), but RELAXED_CHECKSUMS \
             records {shown} for RELAXATION_VERSION {RELAXATION_VERSION}: the relaxation \
             changed. Bump RELAXATION_VERSION and record the new checksum, for builds with and \
             without FMA (RUSTFLAGS=\"-C target-cpu=x86-64\" cargo test -p sph-apps --lib glass)"
        );
    }

    #[test]
    fn a_glass_of_another_relaxation_version_is_refused_and_replaced() {
        let dir = crate::test_dir("glass-version");
        let spec = GlassSpec {
            side: MIN_SIDE,
            ..GlassSpec::default()
        };
        assert!(spec
            .file_name()
            .ends_with(&format!("_v{RELAXATION_VERSION}.h5")));
        let glass = Glass {
            spec,
            pos: vec![[0.5; 3]; MIN_SIDE.pow(3)],
            report: Relaxation {
                steps: 0,
                rho_scatter_start: 0.0,
                rho_scatter: 0.0,
                min_pair_start: 0.0,
                min_pair: 0.0,
            },
        };
        let path = dir.join(spec.file_name());
        write(&glass, &path).expect("written");
        assert_eq!(read(&path, &spec).expect("read back"), glass);
        write_version(&glass, &path, RELAXATION_VERSION + 1).expect("written");
        let e = read(&path, &spec).expect_err("another version").to_string();
        assert!(
            e.contains(&spec.file_name())
                && e.contains(&format!("relaxation version {}", RELAXATION_VERSION + 1)),
            "{e}"
        );
        // The cache relaxes a glass of this version in its place.
        let fresh = cached(&spec, &dir).expect("relaxed");
        assert_ne!(fresh.pos, glass.pos);
        assert_eq!(read(&path, &spec).expect("now this version"), fresh);
    }
}
