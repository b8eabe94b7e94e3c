//! The test cases: initial conditions, the scheme each needs, and its
//! reference solution.
//!
//! A case is a type implementing [`Case`], in its own module, listed once
//! in [`CASES`]: the command line (`sphexa cases`, `sphexa run CASE`), its
//! help text, its unknown-case error and the tests all read that list.
//! Adding a case is one new file here and one line in the `registry!`
//! list below (`module::CaseType`), which declares the module and lists the
//! case in [`CASES`].
//!
//! ```
//! use sph_apps::cases;
//! use sph_core::HydroConfig;
//!
//! let case = cases::lookup("sedov").unwrap();
//! // The case's scheme is applied by `setup` itself.
//! let scene = case.setup(8, HydroConfig::default()).unwrap();
//! assert_eq!(scene.particles.len(), 8 * 8 * 8);
//! assert!(cases::lookup("sedov-taylor").is_err());
//! ```

use crate::reference::{FlowState, Gresho, Noh, Riemann, Sedov};
use crate::AppError;
use sph_core::{FieldSet, HydroConfig, Particles, TimeSteps};
use sph_tree::BoundingBox;

pub mod scene;
pub(crate) mod scheme;
pub(crate) mod scheme_options;
pub(crate) mod setup;

pub use scheme::{FirstStep, Physics, Scheme, SchemeOverrides};
pub use scheme_options::{scheme_option, SchemeOption, Setting, Values, SCHEME_OPTIONS};
pub use setup::{initial_h, Share};

/// Declares each case's module and lists its type in [`CASES`]: one line
/// per case.
macro_rules! registry {
    ($($module:ident :: $case:ident),* $(,)?) => {
        $(pub mod $module;)*
        /// Every case, in listing order: the only list of cases.
        pub static CASES: &[&dyn Case] = &[$(&$module::$case),*];
    };
}

registry! {
    sedov::SedovBlast,
    noh::NohImplosion,
    square_patch::SquarePatch,
    square_patch_slab::SquarePatchSlab,
    evrard::EvrardCollapse,
    sod::SodTube,
    gresho::GreshoVortex,
    isobaric_cube::IsobaricCube,
    kelvin_helmholtz::KelvinHelmholtz,
    wind_shock::WindShock,
    turbulence::DrivenTurbulence,
}

/// Every case, in listing order (the same as [`CASES`]).
pub fn registry() -> &'static [&'static dyn Case] {
    CASES
}

/// The names of all cases, in listing order.
pub fn names() -> Vec<&'static str> {
    CASES.iter().map(|c| c.name()).collect()
}

/// Looks a case up by name.
pub fn find(name: &str) -> Option<&'static dyn Case> {
    CASES.iter().copied().find(|c| c.name() == name)
}

/// Looks a case up by name; an unknown name is a usage error that names it
/// and lists the cases there are.
pub fn lookup(name: &str) -> Result<&'static dyn Case, AppError> {
    find(name).ok_or_else(|| {
        AppError::Usage(format!(
            "unknown case '{name}'; available: {}",
            names().join(", ")
        ))
    })
}

/// A test case: what it is called, what it runs by default, how it starts
/// and what it is compared with.
///
/// Implementors write the listing methods, [`default_scheme`],
/// [`initial_state`] and, where the case has them, [`reference`] and
/// [`energies`]. Callers use [`setup`] or [`setup_with`], which apply the
/// case's scheme (with the caller's overrides) before the set-up sees the
/// configuration, so no caller can forget it; implementors do not override
/// these two.
///
/// [`default_scheme`]: Case::default_scheme
/// [`initial_state`]: Case::initial_state
/// [`reference`]: Case::reference
/// [`energies`]: Case::energies
/// [`setup`]: Case::setup
/// [`setup_with`]: Case::setup_with
pub trait Case: Sync + std::fmt::Debug {
    /// Name on the command line (lower case, words joined by `-`).
    fn name(&self) -> &'static str {
        self.listing().name
    }

    /// What the case is called and runs by default.
    fn listing(&self) -> Listing;

    /// One line for listings.
    fn description(&self) -> &'static str {
        self.listing().description
    }

    /// Default particles per side of the initial lattice.
    fn default_side(&self) -> usize {
        self.listing().side
    }

    /// Default end time.
    fn default_end_time(&self) -> f64 {
        self.listing().end_time
    }

    /// The scheme the case runs with unless overridden.
    fn default_scheme(&self) -> Scheme;

    /// How the case's particles share time steps unless `--time-steps`
    /// says otherwise: block steps for every case. A stirred box's
    /// particles all need about the same step: driven turbulence at 16^3
    /// does 8% fewer updates under them in 40% more sub-steps, in 1.00-1.03x
    /// the global run's wall time, and conserves momentum to 1e-4 of M v
    /// rather than to round-off (`--time-steps global` keeps it there).
    fn default_time_steps(&self) -> TimeSteps {
        TimeSteps::Block
    }

    /// The equation of state and self-gravity of the case (default: an
    /// ideal gas with gamma = 5/3, no self-gravity).
    fn physics(&self) -> Physics {
        Physics::IDEAL_GAS
    }

    /// The initial particles, box and first time step for the `request`'s
    /// `side` particles per side. Its `config` already carries the scheme
    /// (see [`Case::setup`]); use [`field_set`] for the particle fields it
    /// needs. Only the particles of its `share` are built (global ids, in
    /// the case's order): a distributed run never holds the whole initial
    /// state on one rank.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError>;

    /// The analytic solution to compare `initial` with, if any.
    fn reference(
        &self,
        side: usize,
        initial: &InitialState,
    ) -> Result<Option<Reference>, AppError> {
        let _ = (side, initial);
        Ok(None)
    }

    /// Reference energies over time, if any.
    fn energies(&self) -> Option<&'static [EnergyPoint]> {
        None
    }

    /// A quantity the case tracks every step (`curve.csv`, `curve.png`),
    /// if any.
    fn curve(&self) -> Option<Curve> {
        None
    }

    /// The scene for `side` particles per side with the case's own scheme
    /// written over `config` (whose other settings, e.g. neighbour counts,
    /// Courant factor, conductivity, curve, gravity's opening angle, are
    /// kept).
    fn setup(&self, side: usize, config: HydroConfig) -> Result<Scene, AppError> {
        self.setup_with(side, config, &SchemeOverrides::default())
    }

    /// As [`Case::setup`], with the case's scheme changed by `overrides`.
    fn setup_with(
        &self,
        side: usize,
        config: HydroConfig,
        overrides: &SchemeOverrides,
    ) -> Result<Scene, AppError> {
        self.setup_share(side, config, overrides, Share::WHOLE, &Layout::default())
    }

    /// As [`Case::setup_with`], holding only the particles of `share`
    /// (one rank's part of a distributed run).
    fn setup_share(
        &self,
        side: usize,
        mut config: HydroConfig,
        overrides: &SchemeOverrides,
        share: Share,
        layout: &Layout,
    ) -> Result<Scene, AppError> {
        if side == 0 {
            return Err(AppError::Usage(format!(
                "case {}: 0 particles per side; at least 1 is needed",
                self.name()
            )));
        }
        overrides.apply(self.default_scheme(), self.physics(), &mut config);
        let request = Request {
            side,
            config: &config,
            share,
            layout,
        };
        let initial = self.initial_state(&request)?;
        let reference = self.reference(side, &initial)?;
        Ok(Scene {
            case: self.name(),
            total: initial.total,
            particles: initial.particles,
            bbox: initial.bbox,
            config,
            dt0: initial.dt0,
            reference,
            energies: self.energies(),
            curve: self.curve(),
        })
    }
}

/// What a case builds its initial state for ([`Case::initial_state`]).
#[derive(Debug, Clone, Copy)]
pub struct Request<'a> {
    /// Particles per side of the initial lattice (or per unit length).
    pub side: usize,
    /// The run's configuration, the case's scheme already applied.
    pub config: &'a HydroConfig,
    /// The particles to build.
    pub share: Share,
    /// Lattice or glass.
    pub layout: &'a Layout,
}

/// How a case places its particles.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// Glass where the case starts from one ([`crate::glass`], relaxed
    /// with `kernel` and the run's neighbour counts, cached in `dir`),
    /// cubic lattices elsewhere.
    Glass {
        /// The run's kernel.
        kernel: sph_kernels::KernelChoice,
        /// The glass cache.
        dir: std::path::PathBuf,
    },
    /// Cubic lattices everywhere.
    Lattice,
}

impl Layout {
    /// The glass block of `side`^3 particles relaxed with the run's
    /// kernel and the neighbour counts of `config` (from the cache, or
    /// relaxed and stored there), or `None` for cubic lattices.
    ///
    /// # Errors
    /// A side outside the glass's range, a failed relaxation, or a cache
    /// folder that cannot be written.
    pub fn glass(
        &self,
        side: usize,
        config: &HydroConfig,
    ) -> Result<Option<crate::glass::Glass>, AppError> {
        match self {
            Layout::Lattice => Ok(None),
            Layout::Glass { kernel, dir } => {
                let spec = crate::glass::GlassSpec {
                    side,
                    kernel: *kernel,
                    ng0: config.neighbors.ng0,
                    ngmax: config.neighbors.ngmax,
                };
                crate::glass::cached(&spec, dir).map(Some)
            }
        }
    }
}

impl Default for Layout {
    /// Glass with the default kernel, cached in
    /// [`crate::glass::default_cache_dir`].
    fn default() -> Self {
        Layout::Glass {
            kernel: sph_kernels::KernelChoice::default(),
            dir: crate::glass::default_cache_dir(),
        }
    }
}

/// A case's name, one-line description and defaults (for listings and
/// for runs that do not say otherwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Listing {
    /// Name on the command line (lower case, words joined by `-`).
    pub name: &'static str,
    /// One line for listings.
    pub description: &'static str,
    /// Default particles per side of the initial lattice.
    pub side: usize,
    /// Default end time.
    pub end_time: f64,
}

/// What a case starts from, before the scheme and references are attached.
#[derive(Debug, Clone)]
pub struct InitialState {
    /// Particles of all ranks together.
    pub total: usize,
    /// Initial particles (this rank's share).
    pub particles: Particles,
    /// Simulation box.
    pub bbox: BoundingBox,
    /// First time step (the integrator's `dt_{-1}`).
    pub dt0: f64,
}

/// The optional particle fields `config` needs (IAD matrix, grad-h factor,
/// gravitational potential).
pub fn field_set(config: &HydroConfig) -> FieldSet {
    config.fields()
}

/// Reference energies of a case at one time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EnergyPoint {
    /// Time.
    pub t: f64,
    /// Kinetic energy.
    pub e_kin: f64,
    /// Internal (thermal) energy.
    pub e_int: f64,
    /// Gravitational energy.
    pub e_grav: f64,
}

/// An analytic solution to compare against, a function of one coordinate
/// ([`Reference::coordinate`]): the radius for the spherical solutions,
/// `|x|` for the doubled shock tube.
#[derive(Debug, Clone)]
pub enum Reference {
    /// Sedov-Taylor blast wave centred at the origin.
    Sedov(Sedov),
    /// Noh implosion centred at the origin.
    Noh(Noh),
    /// Doubled periodic shock tube along x ([`Tube`]).
    Tube(Tube),
    /// A stationary vortex about the z axis: the coordinate is the
    /// cylindrical radius, the speed `v_phi`; compared out to
    /// [`VORTEX_EXTENT`].
    Vortex(Gresho),
    /// A cube of one gas in another at rest ([`Stationary`]).
    Stationary(Stationary),
}

/// Gas at rest: `inner` (density, pressure) where the max norm of the
/// position is below `half`, `outer` elsewhere. The coordinate is that max
/// norm, `max(|x|, |y|, |z|)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stationary {
    /// Density and pressure inside.
    pub inner: [f64; 2],
    /// Density and pressure outside.
    pub outer: [f64; 2],
    /// Half the side of the inner cube.
    pub half: f64,
    /// Adiabatic index (for the internal energy).
    pub gamma: f64,
}

impl Stationary {
    /// The state at max-norm distance `r`.
    pub fn state(&self, r: f64) -> FlowState {
        if r.is_nan() {
            return FlowState::NAN;
        }
        let [rho, p] = if r < self.half {
            self.inner
        } else {
            self.outer
        };
        FlowState {
            rho,
            p,
            v: 0.0,
            u: p / ((self.gamma - 1.0) * rho),
        }
    }
}

/// Cylindrical radius out to which a vortex's L1 errors are taken (the
/// half-width of the box: the corners are at rest and would dilute them).
pub const VORTEX_EXTENT: f64 = 0.5;

/// A doubled shock tube: the `left` gas of a Riemann problem fills
/// `|x| < interface`, the `right` gas the rest of a periodic box along x,
/// so there are two mirror-image Riemann problems, at `x = +interface` and
/// `x = -interface`. Folded onto `s = |x|` (velocity `sign(x) v_x`) both
/// are the one problem at `s = interface`, until their waves meet.
#[derive(Debug, Clone)]
pub struct Tube {
    /// The problem at `x = +interface` (left gas inside).
    pub riemann: Riemann,
    /// Where the two gases meet at t = 0.
    pub interface: f64,
}

impl Tube {
    /// Position of the shock (into the outer gas) at `t`, in `s = |x|`.
    pub fn shock_position(&self, t: f64) -> f64 {
        self.interface + self.riemann.waves().right_head * t
    }

    /// Position of the contact at `t`, in `s = |x|`.
    pub fn contact_position(&self, t: f64) -> f64 {
        self.interface + self.riemann.v_star() * t
    }
}

impl Reference {
    /// The coordinate the solution depends on: the distance from the
    /// origin, or `|x|` for the tube.
    pub fn coordinate(&self, pos: [f64; 3]) -> f64 {
        match self {
            Reference::Sedov(_) | Reference::Noh(_) => nalgebra::Vector3::from(pos).norm(),
            Reference::Tube(_) => pos[0].abs(),
            Reference::Vortex(_) => pos[0].hypot(pos[1]),
            Reference::Stationary(_) => pos.iter().fold(0.0f64, |m, c| m.max(c.abs())),
        }
    }

    /// Whether a particle at `coordinate` enters the L1 errors.
    pub fn covers(&self, coordinate: f64) -> bool {
        match self {
            Reference::Vortex(_) => coordinate <= VORTEX_EXTENT,
            _ => true,
        }
    }

    /// The particle speed compared with [`Reference::reference_speed`]:
    /// `|v|` for the spherical solutions, `sign(x) v_x` for the tube.
    pub fn flow_speed(&self, pos: [f64; 3], vel: [f64; 3]) -> f64 {
        match self {
            Reference::Sedov(_) | Reference::Noh(_) | Reference::Stationary(_) => {
                nalgebra::Vector3::from(vel).norm()
            }
            Reference::Tube(_) => {
                if pos[0] < 0.0 {
                    -vel[0]
                } else {
                    vel[0]
                }
            }
            Reference::Vortex(_) => {
                let r = pos[0].hypot(pos[1]);
                if r > 0.0 {
                    (pos[0] * vel[1] - pos[1] * vel[0]) / r
                } else {
                    0.0
                }
            }
        }
    }

    /// The reference's speed at a state: `|v_r|` for the spherical
    /// solutions, the signed velocity along the folded tube.
    pub fn reference_speed(&self, state: &FlowState) -> f64 {
        match self {
            Reference::Sedov(_) | Reference::Noh(_) | Reference::Stationary(_) => state.v.abs(),
            Reference::Tube(_) | Reference::Vortex(_) => state.v,
        }
    }

    /// State at coordinate `r` and time `t`; `v` is the velocity along
    /// the coordinate.
    pub fn state(&self, r: f64, t: f64) -> FlowState {
        match self {
            Reference::Sedov(s) => s.state(r, t),
            Reference::Noh(n) => n.state(r, t),
            Reference::Tube(tube) => tube.riemann.state(r - tube.interface, t),
            Reference::Vortex(g) => g.state(r),
            Reference::Stationary(s) => s.state(r),
        }
    }

    /// Shock radius (the tube: shock position in `|x|`) at `t`; `None`
    /// for a flow without shock.
    pub fn shock_radius(&self, t: f64) -> Option<f64> {
        match self {
            Reference::Sedov(s) => Some(s.shock_radius(t)),
            Reference::Noh(n) => Some(n.shock_radius(t)),
            Reference::Tube(tube) => Some(tube.shock_position(t)),
            Reference::Vortex(_) | Reference::Stationary(_) => None,
        }
    }
}

/// Everything a run of a case starts from.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Case name.
    pub case: &'static str,
    /// Particles of all ranks together.
    pub total: usize,
    /// Initial particles: all of them, or this rank's share
    /// ([`Case::setup_share`]).
    pub particles: Particles,
    /// Simulation box.
    pub bbox: BoundingBox,
    /// The scheme the case needs.
    pub config: HydroConfig,
    /// First time step (the integrator's `dt_{-1}`).
    pub dt0: f64,
    /// Analytic solution, if any.
    pub reference: Option<Reference>,
    /// Reference energies over time, if any.
    pub energies: Option<&'static [EnergyPoint]>,
    /// The quantity tracked every step, if any.
    pub curve: Option<Curve>,
}

/// Most per-particle sums a [`Curve`] may use.
pub const CURVE_MAX_SUMS: usize = 8;

/// A case's observable over time, built from sums over all particles so
/// that it is exact and the same on any number of ranks: each step the
/// run adds `terms` of every particle into `sums` exact sums, reduces them
/// over the ranks and writes `finish` of the totals as one line of
/// `curve.csv` (`step, t, columns...`); `curve.png` plots the columns with
/// the `reference` points as markers.
#[derive(Debug, Clone, Copy)]
pub struct Curve {
    /// Axis label of the plot.
    pub label: &'static str,
    /// Names of the values `finish` returns (the CSV columns after `t`).
    pub columns: &'static [&'static str],
    /// Number of per-particle sums (at most [`CURVE_MAX_SUMS`]).
    pub sums: usize,
    /// Writes particle `i`'s term of each sum into `out` (`sums` long).
    pub terms: fn(&Particles, usize, &mut [f64]),
    /// The values (one per column) from the totals.
    pub finish: fn(&[f64]) -> Vec<f64>,
    /// Reference `(t, value)` points of the first column, if any.
    pub reference: &'static [(f64, f64)],
}

/// Particles of an `n^3` lattice of cell centres in the cube
/// `[lo, lo + len)^3`, in x-fastest order.
pub fn cube_lattice(n: usize, lo: f64, len: f64) -> impl Iterator<Item = [f64; 3]> {
    let dx = len / n as f64;
    (0..n * n * n).map(move |i| {
        let c = [i % n, i / n % n, i / (n * n)];
        c.map(|k| lo + (k as f64 + 0.5) * dx)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_command_line_friendly() {
        let names = names();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "case {n} listed twice");
            assert!(
                !n.is_empty()
                    && n.chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'),
                "case name {n:?}"
            );
            assert_eq!(lookup(n).expect("listed case").name(), *n);
        }
    }

    #[test]
    fn unknown_case_names_itself_and_the_cases() {
        let e = lookup("sedov-taylor").unwrap_err().to_string();
        assert!(e.contains("'sedov-taylor'"), "{e}");
        for n in names() {
            assert!(e.contains(n), "{e}");
        }
    }

    #[test]
    fn every_case_sets_up_with_its_own_scheme() {
        for case in registry() {
            assert!(case.default_side() >= 4, "{}", case.name());
            assert!(case.default_end_time() > 0.0, "{}", case.name());
            assert!(!case.description().is_empty(), "{}", case.name());
            // Whatever scheme the caller's config had, the case's wins.
            let mut scheme = Scheme::PAPER;
            scheme.gradients = sph_core::Gradients::Kernel;
            scheme.grad_h = false;
            scheme.viscosity = sph_core::Viscosity::Constant { alpha: 3.0 };
            scheme.conductivity = Some(1.0);
            let wrong = HydroConfig::with_scheme(scheme);
            // 8 per side, 32 for wind-shock (its 0.25-wide box needs 28),
            // 16 for turbulence (whole glass blocks of 16).
            let side = match case.name() {
                "wind-shock" => 32,
                "turbulence" => 16,
                _ => 8,
            };
            let layout = Layout::Glass {
                kernel: sph_kernels::KernelChoice::default(),
                dir: crate::test_glass_dir(),
            };
            let scene = case
                .setup_share(
                    side,
                    wrong,
                    &SchemeOverrides::default(),
                    Share::WHOLE,
                    &layout,
                )
                .expect("set-up");
            let mut want = HydroConfig::default();
            SchemeOverrides::default().apply(case.default_scheme(), case.physics(), &mut want);
            assert_eq!(scene.config, want, "{}", case.name());
            assert_eq!(scene.case, case.name());
            let p = &scene.particles;
            assert!(!p.is_empty(), "{}", case.name());
            assert_eq!(p.fields(), field_set(&want), "{}", case.name());
            assert!(p.h.iter().all(|&h| h > 0.0), "{}", case.name());
            assert!(scene.dt0 > 0.0);
            assert_eq!(
                scene.energies.map(<[EnergyPoint]>::len),
                case.energies().map(<[EnergyPoint]>::len)
            );
        }
    }

    #[test]
    fn the_default_gas_is_the_one_the_references_assume() {
        let gas = sph_core::Eos::IdealGas {
            gamma: sedov::GAMMA,
        };
        assert_eq!(lookup("sedov").unwrap().physics().eos, gas);
        let gas = sph_core::Eos::IdealGas { gamma: noh::GAMMA };
        assert_eq!(lookup("noh").unwrap().physics().eos, gas);
    }

    #[test]
    fn overrides_reach_the_scene() {
        let case = lookup("sedov").expect("sedov");
        let o = SchemeOverrides::default()
            .with("gradients", Setting::Name("kernel"))
            .and_then(|o| o.with("alpha", Setting::Number(0.5)))
            .expect("scheme options");
        let scene = case
            .setup_with(5, HydroConfig::default(), &o)
            .expect("set-up");
        assert_eq!(scene.config.scheme.gradients, sph_core::Gradients::Kernel);
        assert_eq!(scene.config.scheme.alpha(), 0.5);
        assert!(case.setup(0, HydroConfig::default()).is_err());
    }
}
