//! A scene of the user's own: `sphexa run --init FILE` with no case. The
//! particles are the file's; the physics comes from the command line or,
//! where it is silent, from the file's attributes (SPH-EXA's names: `box`,
//! `boundaryType`, `gamma`, `gravConstant`, `minDt`; ours: `box`,
//! `periodic`). Nothing that matters is guessed: what neither says is an
//! error naming the option to give.
//!
//! | physics | option | file attribute | when neither says |
//! | --- | --- | --- | --- |
//! | boundaries | `--boundary periodic\|open\|P,P,O` | `periodic` (ours, 1 = periodic), `boundaryType` (SPH-EXA: 0 open, 1 periodic) | error |
//! | box | `--box LO:HI` or `X0:X1,Y0:Y1,Z0:Z1` | `box` | error if an axis is periodic; open axes follow the particles |
//! | equation of state | `--eos` | `gamma` (an ideal gas) | error |
//! | self-gravity | `--gravity on\|off`, `--softening` | `gravConstant` (on with G when non-zero) | off in a periodic box, else error |
//! | end | `--end-time`, `--steps` | | error |
//!
//! The scheme is [`SCHEME`] (`--scheme` and the scheme options change it
//! as for any case); the first step comes from the time-step criteria
//! unless `--first-step` says otherwise.
//!
//! ```
//! use sph_apps::cases::scene::{FileAttrs, SceneOptions, UserScene};
//!
//! // A blast in a periodic unit cube whose file gives its box and gamma.
//! let file = FileAttrs {
//!     bbox: Some([-0.5, 0.5, -0.5, 0.5, -0.5, 0.5]),
//!     periodic: Some([true; 3]),
//!     gamma: Some(5.0 / 3.0),
//!     ..FileAttrs::default()
//! };
//! let scene = UserScene::resolve("blast.h5", &file, &SceneOptions::default(), 0.1).unwrap();
//! assert!(scene.physics.softening.is_none()); // no self-gravity in a periodic box
//!
//! // An isolated cloud must say whether it gravitates.
//! let cloud = FileAttrs {
//!     periodic: Some([false; 3]),
//!     gamma: Some(5.0 / 3.0),
//!     ..FileAttrs::default()
//! };
//! let e = UserScene::resolve("cloud.h5", &cloud, &SceneOptions::default(), 1.0).unwrap_err();
//! assert!(e.to_string().contains("--gravity on"));
//! ```

use super::{field_set, Case, InitialState, Listing, Physics, Request, Scheme};
use crate::AppError;
use sph_core::{Eos, Particles};
use sph_tree::{Boundary, BoundingBox};

/// The name of a scene's runs (`out/scene`, the `case` of its checkpoints).
pub const NAME: &str = "scene";

/// The scheme a scene runs with: `gas` ([`Scheme::GAS`]), issue 42's
/// default for the ideal-gas cases.
pub const SCHEME: Scheme = Scheme::GAS;

/// First time step when the file gives none (`minDt`): only the
/// integrator's `dt_{-1}`, since a scene's first step is the criteria's.
pub const DT0: f64 = 1e-6;

/// What a file says of its physics: the attributes of its step group.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FileAttrs {
    /// `box`: `xmin, xmax, ymin, ymax, zmin, zmax`.
    pub bbox: Option<[f64; 6]>,
    /// Periodic axes (`periodic`, or `boundaryType` 1 = periodic, 0 =
    /// open).
    pub periodic: Option<[bool; 3]>,
    /// `gamma`: an ideal gas with this adiabatic index.
    pub gamma: Option<f64>,
    /// `gravConstant`: self-gravity with this G when not zero.
    pub grav_constant: Option<f64>,
    /// `minDt`: the step before the first.
    pub dt: Option<f64>,
}

impl FileAttrs {
    /// The attributes of an H5Part step ([`sph_io::foreign`]). A
    /// `boundaryType` other than open (0) or periodic (1) on some axis, or
    /// an attribute of the wrong length, is refused by name.
    pub fn of(path: &str, step: &sph_io::foreign::ForeignStep) -> Result<Self, AppError> {
        let scalar = |name: &str| -> Result<Option<f64>, AppError> {
            match step.number(name) {
                None => Ok(None),
                Some([v]) if v.is_finite() => Ok(Some(*v)),
                Some(v) => Err(AppError::Usage(format!(
                    "--init {path}: attribute '{name}' is {v:?}; expected one finite number"
                ))),
            }
        };
        let axes = |name: &str, open: f64, periodic: f64| -> Result<Option<[bool; 3]>, AppError> {
            match step.number(name) {
                None => Ok(None),
                Some(v) if v.len() == 3 && v.iter().all(|&x| x == open || x == periodic) => {
                    Ok(Some([v[0] == periodic, v[1] == periodic, v[2] == periodic]))
                }
                Some(v) => Err(AppError::Usage(format!(
                    "--init {path}: attribute '{name}' is {v:?}; expected 3 values, {open} (open) or {periodic} (periodic), or give --boundary"
                ))),
            }
        };
        Ok(Self {
            bbox: step.bbox,
            periodic: axes("periodic", 0.0, 1.0)?.or(axes("boundaryType", 0.0, 1.0)?),
            gamma: scalar("gamma")?,
            grav_constant: scalar("gravConstant")?,
            dt: scalar("minDt")?.filter(|&d| d > 0.0),
        })
    }
}

/// `--gravity`: what the command line says of self-gravity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SceneGravity {
    /// No self-gravity.
    Off,
    /// Self-gravity with the file's `gravConstant` (1 if it has none, or 0).
    On,
    /// Self-gravity with this gravitational constant.
    Constant(f64),
}

/// `on`, `off` or G, which `--gravity` reads back.
impl std::fmt::Display for SceneGravity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneGravity::Off => f.write_str("off"),
            SceneGravity::On => f.write_str("on"),
            SceneGravity::Constant(g) => write!(f, "{g}"),
        }
    }
}

/// What the command line says of a scene's physics.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SceneOptions {
    /// `--eos`.
    pub eos: Option<Eos>,
    /// `--box`.
    pub bbox: Option<[f64; 6]>,
    /// `--boundary`.
    pub boundary: Option<[Boundary; 3]>,
    /// `--gravity`.
    pub gravity: Option<SceneGravity>,
    /// `--softening`.
    pub softening: Option<f64>,
}

/// A scene: its physics, box and end time, resolved from the options and
/// the file ([`UserScene::resolve`]). The particles replace the empty
/// initial state it builds (`sphexa run` loads them as for `--init` of a
/// case), so that each rank reads only its share.
#[derive(Debug, Clone, PartialEq)]
pub struct UserScene {
    /// Equation of state, self-gravity (its softening), no stirring.
    pub physics: Physics,
    /// Gravitational constant (1 without self-gravity).
    pub g: f64,
    /// The box: the file's or the options'; open axes are refitted to the
    /// particles at the first step.
    pub bbox: BoundingBox,
    /// The step before the first (the file's `minDt`, else [`DT0`]).
    pub dt0: f64,
    /// End time of the run.
    pub end_time: f64,
}

impl UserScene {
    /// The scene with the file attributes `file` and options `opts`, run
    /// to `end_time`. Errors start with `source` (e.g. `--init FILE (no
    /// case)`) and name what to give where the physics is missing or
    /// contradicts itself.
    pub fn resolve(
        source: &str,
        file: &FileAttrs,
        opts: &SceneOptions,
        end_time: f64,
    ) -> Result<Self, AppError> {
        let usage = |what: String| AppError::Usage(format!("{source}: {what}"));
        let boundary = match (opts.boundary, file.periodic) {
            (Some(b), _) => b,
            (None, Some(p)) => p.map(|q| if q { Boundary::Periodic } else { Boundary::Open }),
            (None, None) => {
                return Err(usage(
                    "its boundaries are not said (no attribute 'periodic' or 'boundaryType'); give --boundary periodic, --boundary open, or one per axis, e.g. --boundary periodic,periodic,open".into(),
                ))
            }
        };
        let periodic = boundary.contains(&Boundary::Periodic);
        let lo_hi = match (opts.bbox, file.bbox) {
            (Some(b), _) | (None, Some(b)) => b,
            // Open axes are refitted to the particles at the first step.
            (None, None) if !periodic => [-1.0, 1.0, -1.0, 1.0, -1.0, 1.0],
            (None, None) => {
                return Err(usage(
                    "a periodic axis needs the box, and the file has no attribute 'box'; give --box LO:HI (a cube) or --box X0:X1,Y0:Y1,Z0:Z1".into(),
                ))
            }
        };
        let bbox = BoundingBox::new(
            [lo_hi[0], lo_hi[2], lo_hi[4]],
            [lo_hi[1], lo_hi[3], lo_hi[5]],
            boundary,
        )
        .map_err(|e| usage(format!("box {lo_hi:?}: {e}")))?;
        let eos = match (opts.eos, file.gamma) {
            (Some(e), _) => e,
            (None, Some(gamma)) if gamma > 1.0 => Eos::IdealGas { gamma },
            (None, Some(gamma)) => {
                return Err(usage(format!(
                    "attribute 'gamma' is {gamma}; an ideal gas needs gamma > 1: give --eos ({})",
                    sph_core::eos::EOS_FORMS
                )))
            }
            (None, None) => {
                return Err(usage(format!(
                    "the equation of state is not said (no attribute 'gamma'); give --eos, e.g. --eos ideal:1.6667 ({})",
                    sph_core::eos::EOS_FORMS
                )))
            }
        };
        let file_g = file.grav_constant.filter(|&g| g != 0.0);
        // Self-gravity's constant, or none.
        let g = match (opts.gravity, file.grav_constant) {
            (Some(SceneGravity::Off), _) => None,
            (Some(SceneGravity::On), _) => Some(file_g.unwrap_or(1.0)),
            (Some(SceneGravity::Constant(g)), _) => Some(g),
            (None, Some(_)) => file_g,
            (None, None) if periodic => None,
            (None, None) => {
                return Err(usage(
                    "self-gravity is not said for an open box (no attribute 'gravConstant'); give --gravity on (pairs softened within --softening S times h_i + h_j, default 1) or --gravity off".into(),
                ))
            }
        };
        let gravity = g.is_some();
        if gravity && periodic {
            return Err(usage(format!(
                "self-gravity needs open boundaries on every axis (periodic gravity needs Ewald sums, which this code does not have); the boundaries are {boundary:?}: give --gravity off or --boundary open"
            )));
        }
        if opts.softening.is_some() && !gravity {
            return Err(usage(
                "--softening applies to self-gravity, which is off; give --gravity on or leave --softening out".into(),
            ));
        }
        let default_softening = sph_gravity::GravityParams::default().softening;
        Ok(Self {
            physics: Physics {
                eos,
                softening: gravity.then(|| opts.softening.unwrap_or(default_softening)),
                courant: None,
                stirring: None,
            },
            g: g.unwrap_or(1.0),
            bbox,
            dt0: file.dt.unwrap_or(DT0),
            end_time,
        })
    }
}

impl Case for UserScene {
    fn listing(&self) -> Listing {
        Listing {
            name: NAME,
            description: "the particles of --init FILE with the physics of the options and the file's attributes",
            side: 1,
            end_time: self.end_time,
        }
    }

    fn default_scheme(&self) -> Scheme {
        SCHEME
    }

    fn physics(&self) -> Physics {
        self.physics
    }

    /// No particles: `sphexa run` loads the file's share of each rank in
    /// their place.
    fn initial_state(&self, request: &Request<'_>) -> Result<InitialState, AppError> {
        Ok(InitialState {
            total: 0,
            particles: Particles::new(0, field_set(request.config)),
            bbox: self.bbox,
            dt0: self.dt0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn periodic_blast() -> FileAttrs {
        FileAttrs {
            bbox: Some([0.0, 1.0, 0.0, 1.0, 0.0, 1.0]),
            periodic: Some([true; 3]),
            gamma: Some(1.4),
            ..FileAttrs::default()
        }
    }

    fn message(r: Result<UserScene, AppError>) -> String {
        r.expect_err("refused").to_string()
    }

    #[test]
    fn options_win_over_the_file() {
        let opts = SceneOptions {
            eos: Some(Eos::Isothermal { c0: 2.0 }),
            bbox: Some([-1.0, 1.0, -2.0, 2.0, -3.0, 3.0]),
            ..SceneOptions::default()
        };
        let s = UserScene::resolve("f", &periodic_blast(), &opts, 1.0).unwrap();
        assert_eq!(s.physics.eos, Eos::Isothermal { c0: 2.0 });
        assert_eq!(s.bbox.lo(), [-1.0, -2.0, -3.0]);
        assert_eq!(s.bbox.boundary(), [Boundary::Periodic; 3]);
        assert_eq!(s.dt0, DT0);
        let file = UserScene::resolve("f", &periodic_blast(), &SceneOptions::default(), 1.0);
        assert_eq!(file.unwrap().physics.eos, Eos::IdealGas { gamma: 1.4 });
    }

    #[test]
    fn what_is_unsaid_is_named() {
        let none = SceneOptions::default();
        let bare = FileAttrs::default();
        assert!(message(UserScene::resolve("f.h5", &bare, &none, 1.0)).contains("--boundary"));
        let no_box = FileAttrs {
            bbox: None,
            ..periodic_blast()
        };
        assert!(message(UserScene::resolve("f.h5", &no_box, &none, 1.0)).contains("--box LO:HI"));
        let no_gamma = FileAttrs {
            gamma: None,
            ..periodic_blast()
        };
        assert!(message(UserScene::resolve("f.h5", &no_gamma, &none, 1.0)).contains("--eos"));
        let open = FileAttrs {
            periodic: Some([false; 3]),
            bbox: None,
            ..periodic_blast()
        };
        let m = message(UserScene::resolve("f.h5", &open, &none, 1.0));
        assert!(m.contains("--gravity on") && m.contains("f.h5"), "{m}");
    }

    #[test]
    fn gravity_from_the_file_or_the_options() {
        let open = FileAttrs {
            periodic: Some([false; 3]),
            grav_constant: Some(0.5),
            dt: Some(1e-3),
            ..periodic_blast()
        };
        let s = UserScene::resolve("f", &open, &SceneOptions::default(), 1.0).unwrap();
        assert_eq!((s.physics.softening, s.g, s.dt0), (Some(1.0), 0.5, 1e-3));
        let off = SceneOptions {
            gravity: Some(SceneGravity::Off),
            ..SceneOptions::default()
        };
        let s = UserScene::resolve("f", &open, &off, 1.0).unwrap();
        assert_eq!(s.physics.softening, None);
        let zero = FileAttrs {
            grav_constant: Some(0.0),
            ..open.clone()
        };
        let s = UserScene::resolve("f", &zero, &SceneOptions::default(), 1.0).unwrap();
        assert_eq!(s.physics.softening, None);
        let on = SceneOptions {
            gravity: Some(SceneGravity::On),
            softening: Some(0.25),
            ..SceneOptions::default()
        };
        let s = UserScene::resolve("f", &zero, &on, 1.0).unwrap();
        assert_eq!((s.physics.softening, s.g), (Some(0.25), 1.0));
        let g2 = SceneOptions {
            gravity: Some(SceneGravity::Constant(2.0)),
            ..SceneOptions::default()
        };
        let s = UserScene::resolve("f", &open, &g2, 1.0).unwrap();
        assert_eq!((s.physics.softening, s.g), (Some(1.0), 2.0));
        // Periodic gravity and softening without gravity are refused.
        let m = message(UserScene::resolve("f", &periodic_blast(), &on, 1.0));
        assert!(m.contains("Ewald"), "{m}");
        let soft = SceneOptions {
            softening: Some(0.5),
            ..SceneOptions::default()
        };
        let m = message(UserScene::resolve("f", &periodic_blast(), &soft, 1.0));
        assert!(m.contains("--softening"), "{m}");
    }
}
