//! Turbulence driving after Federrath et al. (2010), as SPH-EXA implements
//! it (see `docs/turbulence.md`, §0 and §1): a stochastic acceleration
//! field made of the Fourier modes `1 <= |n| <= 3` of a periodic cube,
//! whose complex amplitudes follow Ornstein-Uhlenbeck processes and are
//! projected onto a mix of solenoidal and compressive parts.
//!
//! | part | module |
//! | --- | --- |
//! | mode entries and spectrum | [`modes`] |
//! | Mersenne Twister, polar normals | [`rng`] |
//! | OU phases, projection | [`ou`] |
//! | acceleration at positions | [`field`] |
//!
//! [`Stirring`] holds them together. The solver does not use it yet.

pub mod field;
pub mod modes;
pub mod ou;
pub mod rng;

pub use modes::{ModeSet, Spectrum};
pub use ou::{Amplitudes, OuState};
pub use rng::{Mt19937, Polar};

use crate::CoreError;
use serde::{Deserialize, Serialize};
use sph_tree::BoundingBox;
use std::f64::consts::PI;

/// Parameters of the driving (defaults: SPH-EXA's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StirParams {
    /// Characteristic velocity `v` (0.3: Mach 0.3 for a sound speed of 1);
    /// sets the injected energy and the default correlation time.
    pub velocity: f64,
    /// Energy prefactor (5e-3): the driving energy is `prefactor v^3 / L`.
    pub energy_prefactor: f64,
    /// Solenoidal weight `w` in `[0, 1]` (0.5): 1 is purely solenoidal, 0
    /// purely compressive.
    pub sol_weight: f64,
    /// Seed of the Mersenne Twister (251299), as `std::mt19937` takes it.
    pub seed: u32,
    /// Correlation time of the OU processes; `None` means `L / (2 v)`.
    pub correlation_time: Option<f64>,
    /// Shape of the spectrum.
    pub spectrum: Spectrum,
}

impl Default for StirParams {
    fn default() -> Self {
        Self {
            velocity: 0.3,
            energy_prefactor: 5e-3,
            sol_weight: 0.5,
            seed: 251_299,
            correlation_time: None,
            spectrum: Spectrum::Parabolic,
        }
    }
}

impl StirParams {
    /// Checks `velocity`, `energy_prefactor` and `correlation_time` (when
    /// given) are positive and finite, and `sol_weight` is in `[0, 1]`.
    pub fn validate(&self) -> Result<(), CoreError> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CoreError::Invalid(format!(
                    "stirring: {name} is {v}, expected a positive finite number"
                )))
            }
        };
        positive("velocity", self.velocity)?;
        positive("energy_prefactor", self.energy_prefactor)?;
        if let Some(t) = self.correlation_time {
            positive("correlation_time", t)?;
        }
        if !(0.0..=1.0).contains(&self.sol_weight) {
            return Err(CoreError::Invalid(format!(
                "stirring: sol_weight is {}, expected a number in [0, 1] (1 solenoidal, 0 compressive)",
                self.sol_weight
            )));
        }
        Ok(())
    }
}

/// The keys of the text form of [`StirParams`] and what each takes.
pub const STIR_KEYS: &str = "velocity=V (> 0), energy-prefactor=E (> 0), sol-weight=W (0..1), seed=S (0..2^32), correlation-time=T (> 0, or auto = L / (2 V))";

impl std::fmt::Display for StirParams {
    /// Every key, in the form [`StirParams::from_str`](std::str::FromStr)
    /// reads back to the same values (`velocity=0.3,energy-prefactor=0.005,
    /// sol-weight=0.5,seed=251299,correlation-time=auto`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "velocity={},energy-prefactor={},sol-weight={},seed={},correlation-time=",
            self.velocity, self.energy_prefactor, self.sol_weight, self.seed
        )?;
        match self.correlation_time {
            Some(t) => write!(f, "{t}"),
            None => write!(f, "auto"),
        }
    }
}

impl std::str::FromStr for StirParams {
    type Err = CoreError;

    /// `KEY=VALUE` pairs separated by commas ([`STIR_KEYS`]), each over
    /// the defaults; an empty text is the defaults. The result is
    /// validated.
    ///
    /// ```
    /// use sph_core::stirring::StirParams;
    /// let s: StirParams = "seed=7,sol-weight=1".parse().unwrap();
    /// assert_eq!((s.seed, s.sol_weight, s.velocity), (7, 1.0, 0.3));
    /// assert_eq!(s.to_string().parse::<StirParams>().unwrap(), s);
    /// assert!("sol-weight=2".parse::<StirParams>().is_err());
    /// assert!("speed=1".parse::<StirParams>().is_err());
    /// ```
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let mut s = StirParams::default();
        for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let bad = |why: &str| {
                CoreError::Invalid(format!("stirring '{pair}': {why}; accepted: {STIR_KEYS}"))
            };
            let (key, value) = pair.split_once('=').ok_or_else(|| bad("not KEY=VALUE"))?;
            let (key, value) = (key.trim(), value.trim());
            let number = || value.parse::<f64>().map_err(|_| bad("not a number"));
            match key {
                "velocity" => s.velocity = number()?,
                "energy-prefactor" => s.energy_prefactor = number()?,
                "sol-weight" => s.sol_weight = number()?,
                "seed" => {
                    s.seed = value
                        .parse()
                        .map_err(|_| bad("not an integer in 0..2^32"))?
                }
                "correlation-time" if value == "auto" => s.correlation_time = None,
                "correlation-time" => s.correlation_time = Some(number()?),
                _ => return Err(bad("unknown key")),
            }
        }
        s.validate()?;
        Ok(s)
    }
}

/// The driving state: mode set, OU phases, random-number generator, and the
/// projected amplitudes of the current phases.
///
/// ```
/// use sph_core::stirring::{StirParams, Stirring};
/// use sph_tree::{Boundary, BoundingBox};
///
/// let bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
/// let mut stir = Stirring::new(StirParams::default(), &bbox).unwrap();
/// assert_eq!(stir.entries(), 112);
/// assert!((stir.sigma() - 0.009).abs() < 1e-12); // sqrt(E / T)
///
/// stir.advance(1e-4);
/// let (x, y, z) = ([0.1, -0.3], [0.2, 0.0], [0.4, -0.45]);
/// let (mut ax, mut ay, mut az) = ([0.0; 2], [0.0; 2], [0.0; 2]);
/// stir.accelerate(&x, &y, &z, &mut ax, &mut ay, &mut az);
/// assert_eq!([ax[1], ay[1], az[1]], stir.accelerate_one([x[1], y[1], z[1]]));
///
/// // Checkpoint and restore: the same phases and the same future draws.
/// let (phases, rng) = (stir.phases().to_vec(), stir.rng_state());
/// let mut copy = Stirring::new(StirParams::default(), &bbox).unwrap();
/// copy.restore(&phases, &rng).unwrap();
/// stir.advance(1e-3);
/// copy.advance(1e-3);
/// assert_eq!(stir.phases(), copy.phases());
/// ```
#[derive(Debug, Clone)]
pub struct Stirring {
    params: StirParams,
    modes: ModeSet,
    ou: OuState,
    rng: Mt19937,
    amps: Amplitudes,
    /// `2 pi / L`.
    k1: f64,
    sigma: f64,
    t_corr: f64,
    norm: f64,
}

impl Stirring {
    /// The driving of a periodic cube, its phases drawn from the stationary
    /// distribution. Refuses invalid parameters and a box that is not
    /// periodic on every axis or not cubic (to 1e-12 relative): the modes
    /// need `k L / 2 pi` integer on each axis.
    pub fn new(params: StirParams, bbox: &BoundingBox) -> Result<Self, CoreError> {
        params.validate()?;
        if let Some(axis) = (0..3).find(|&a| !bbox.is_periodic(a)) {
            return Err(CoreError::Invalid(format!(
                "stirring: the box is not periodic along {}; the driving needs a box periodic on every axis",
                ["x", "y", "z"][axis]
            )));
        }
        let l = bbox.lengths();
        if l.iter().any(|&li| (li - l[0]).abs() > 1e-12 * l[0]) {
            return Err(CoreError::Invalid(format!(
                "stirring: the box is {} x {} x {}; the driving needs a cube (sides equal to 1e-12 relative)",
                l[0], l[1], l[2]
            )));
        }
        let length = l[0];
        let energy = params.energy_prefactor * params.velocity.powi(3) / length;
        let t_corr = params
            .correlation_time
            .unwrap_or(length / (2.0 * params.velocity));
        let sigma = (energy / t_corr).sqrt();
        let norm = ou::projection_norm(params.sol_weight);
        let modes = ModeSet::new(length, params.spectrum);
        let mut rng = Mt19937::new(params.seed);
        let ou = OuState::new(modes.len(), sigma, &mut rng);
        let mut s = Self {
            params,
            modes,
            ou,
            rng,
            amps: Amplitudes::default(),
            k1: 2.0 * PI / length,
            sigma,
            t_corr,
            norm,
        };
        s.reproject();
        Ok(s)
    }

    fn reproject(&mut self) {
        self.amps = ou::project(&self.ou, &self.modes, self.params.sol_weight, self.norm);
    }

    /// One OU step over `dt` for every phase, then the new amplitudes.
    pub fn advance(&mut self, dt: f64) {
        self.ou.advance(dt, self.t_corr, self.sigma, &mut self.rng);
        self.reproject();
    }

    /// Writes the stirring acceleration at `(x[i], y[i], z[i])` into
    /// `(ax[i], ay[i], az[i])`, in parallel; bit for bit
    /// [`accelerate_one`](Self::accelerate_one) whatever the thread count.
    ///
    /// # Panics
    ///
    /// If the six slices do not have one length.
    pub fn accelerate(
        &self,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        ax: &mut [f64],
        ay: &mut [f64],
        az: &mut [f64],
    ) {
        field::accelerate(&self.modes, &self.amps, self.k1, x, y, z, ax, ay, az);
    }

    /// The stirring acceleration at one position (the scalar reference).
    pub fn accelerate_one(&self, pos: [f64; 3]) -> [f64; 3] {
        field::accelerate_one(&self.modes, &self.amps, self.k1, pos)
    }

    /// The parameters.
    pub fn params(&self) -> &StirParams {
        &self.params
    }

    /// The mode entries.
    pub fn modes(&self) -> &ModeSet {
        &self.modes
    }

    /// The projected amplitudes of the current phases.
    pub fn amplitudes(&self) -> &Amplitudes {
        &self.amps
    }

    /// Number of mode entries (112 for the default band).
    pub fn entries(&self) -> usize {
        self.modes.len()
    }

    /// Standard deviation of each OU number, `sqrt(E / T)`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Correlation time `T` of the OU processes.
    pub fn correlation_time(&self) -> f64 {
        self.t_corr
    }

    /// Projection norm `sqrt(3) / sqrt(1 - 2w + 3w^2)`.
    pub fn norm(&self) -> f64 {
        self.norm
    }

    /// The OU phases, six per entry (for checkpoints).
    pub fn phases(&self) -> &[f64] {
        &self.ou.phases
    }

    /// The generator's state as 625 exact integers (for checkpoints).
    pub fn rng_state(&self) -> Vec<f64> {
        self.rng.state()
    }

    /// Replaces phases and generator state by checkpointed ones; refuses
    /// wrong lengths, non-finite phases and invalid generator states,
    /// leaving the state unchanged.
    pub fn restore(&mut self, phases: &[f64], rng_state: &[f64]) -> Result<(), CoreError> {
        let want = self.modes.len() * ou::PER_ENTRY;
        if phases.len() != want {
            return Err(CoreError::Invalid(format!(
                "stirring: {} phases given, expected {want} (6 per mode entry)",
                phases.len()
            )));
        }
        if let Some(i) = phases.iter().position(|p| !p.is_finite()) {
            return Err(CoreError::Invalid(format!(
                "stirring: phase {i} is {}, expected a finite number",
                phases[i]
            )));
        }
        self.rng = Mt19937::from_state(rng_state)?;
        self.ou.phases.copy_from_slice(phases);
        self.reproject();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sph_tree::Boundary;

    fn unit_box() -> BoundingBox {
        BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap()
    }

    #[test]
    fn derived_constants_of_the_defaults() {
        let s = Stirring::new(StirParams::default(), &unit_box()).unwrap();
        assert!((s.correlation_time() - 1.0 / 0.6).abs() < 1e-15);
        assert!((s.sigma() - (1.35e-4 * 0.6f64).sqrt()).abs() < 1e-15);
        assert!((s.norm() - 2.0).abs() < 1e-15);
        assert_eq!(s.phases().len(), 672);
        assert_eq!(s.rng_state().len(), 625);
    }

    #[test]
    fn parameter_refusals_name_the_value() {
        let check = |p: StirParams, needle: &str| {
            let e = p.validate().unwrap_err().to_string();
            assert!(e.contains(needle), "{e}");
        };
        let d = StirParams::default();
        check(
            StirParams {
                sol_weight: 1.5,
                ..d
            },
            "sol_weight is 1.5, expected a number in [0, 1]",
        );
        check(
            StirParams {
                sol_weight: f64::NAN,
                ..d
            },
            "sol_weight is NaN",
        );
        check(
            StirParams {
                velocity: -1.0,
                ..d
            },
            "velocity is -1, expected a positive finite",
        );
        check(
            StirParams {
                energy_prefactor: f64::INFINITY,
                ..d
            },
            "energy_prefactor is inf",
        );
        check(
            StirParams {
                correlation_time: Some(0.0),
                ..d
            },
            "correlation_time is 0",
        );
        assert!(d.validate().is_ok());
    }

    #[test]
    fn box_refusals() {
        let p = StirParams::default();
        let open = BoundingBox::new(
            [0.0; 3],
            [1.0; 3],
            [Boundary::Periodic, Boundary::Open, Boundary::Periodic],
        )
        .unwrap();
        let e = Stirring::new(p, &open).unwrap_err().to_string();
        assert!(e.contains("not periodic along y"), "{e}");
        let long =
            BoundingBox::new([0.0; 3], [1.0, 1.0, 1.0 + 1e-9], [Boundary::Periodic; 3]).unwrap();
        let e = Stirring::new(p, &long).unwrap_err().to_string();
        assert!(e.contains("needs a cube"), "{e}");
        // Within 1e-12: accepted.
        let near =
            BoundingBox::new([0.0; 3], [1.0, 1.0, 1.0 + 1e-14], [Boundary::Periodic; 3]).unwrap();
        assert!(Stirring::new(p, &near).is_ok());
    }

    #[test]
    fn restore_refusals_leave_the_state() {
        let mut s = Stirring::new(StirParams::default(), &unit_box()).unwrap();
        let (phases, rng) = (s.phases().to_vec(), s.rng_state());
        let e = s.restore(&phases[1..], &rng).unwrap_err().to_string();
        assert!(e.contains("671 phases given, expected 672"), "{e}");
        let mut bad = phases.clone();
        bad[5] = f64::NAN;
        assert!(s
            .restore(&bad, &rng)
            .unwrap_err()
            .to_string()
            .contains("phase 5 is NaN"));
        assert!(s.restore(&phases, &rng[..3]).is_err());
        assert_eq!(s.phases(), &phases[..]);
        assert_eq!(s.rng_state(), rng);
    }
}
