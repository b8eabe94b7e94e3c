//! The configuration of a hydro run.

use crate::eos::Eos;
use crate::integrate::HUpdate;
use crate::neighbors::NeighborParams;
use crate::scheme::Scheme;
use crate::stirring::StirParams;
use crate::timestep::{TimeSteps, TimestepParams};
use crate::{CoreError, FieldSet};
use sph_gravity::GravityParams;
use sph_tree::Curve;

/// Everything a run of the hydrodynamics needs besides the particles and
/// the kernel: the scheme (discretisation), the physics (EOS, gravity)
/// and the numerical controls.
///
/// It will grow: build one with [`HydroConfig::with_scheme`] (or
/// `Default`) and set fields.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct HydroConfig {
    /// The discretisation: gradients, grad-h, viscosity, conductivity.
    pub scheme: Scheme,
    /// Equation of state.
    pub eos: Eos,
    /// Neighbour-count targets.
    pub neighbors: NeighborParams,
    /// Smoothing-length update rule.
    pub h_update: HUpdate,
    /// Time-step criteria.
    pub timestep: TimestepParams,
    /// Space-filling curve for sorting.
    pub curve: Curve,
    /// Octree bucket size.
    pub bucket: usize,
    /// Self-gravity (tree multipoles; open boxes only), or none.
    pub gravity: Option<GravityParams>,
    /// Measure the time bins a block-step run would give the particles:
    /// each step computes every particle's own step
    /// ([`TimestepParams::particle_dt`]) and reports in
    /// [`StepReport::bins`](super::StepReport::bins) how many could take
    /// `2^k` times the global step. The step and its results do not change.
    pub bin_report: bool,
    /// Turbulence driving ([`crate::stirring`]) in a periodic cube, or
    /// none: each step adds the stirring acceleration, net impulse
    /// removed, and reports its work.
    pub stirring: Option<StirParams>,
    /// One global time step, or block time steps (each particle its own).
    pub time_steps: TimeSteps,
}

impl Default for HydroConfig {
    fn default() -> Self {
        Self {
            scheme: Scheme::PAPER,
            eos: Eos::IdealGas { gamma: 5.0 / 3.0 },
            neighbors: NeighborParams::default(),
            h_update: HUpdate::default(),
            timestep: TimestepParams::default(),
            curve: Curve::Hilbert,
            bucket: 16,
            gravity: None,
            bin_report: false,
            stirring: None,
            time_steps: TimeSteps::Global,
        }
    }
}

impl HydroConfig {
    /// The default controls and physics (ideal gas, 5/3) with `scheme`.
    ///
    /// ```
    /// use sph_core::{HydroConfig, Scheme};
    /// let c = HydroConfig::with_scheme(Scheme::STD);
    /// assert_eq!(c.scheme, Scheme::STD);
    /// assert_eq!(c.bucket, HydroConfig::default().bucket);
    /// ```
    pub fn with_scheme(scheme: Scheme) -> Self {
        Self {
            scheme,
            ..Self::default()
        }
    }

    /// Checks the scheme, the EOS and the numerical controls.
    ///
    /// # Errors
    /// [`CoreError::Invalid`] naming the bad value and what is allowed.
    pub fn validate(&self) -> Result<(), CoreError> {
        self.scheme.validate()?;
        self.eos.validate()?;
        if !self.eos.uses_internal_energy() {
            // Both read u as a thermal energy the EOS does not have.
            let clash = if self.scheme.volume == crate::Volume::PressureEnergy {
                Some("pressure-energy volumes (X = m u)")
            } else if self.scheme.conductivity.is_some() {
                Some("artificial conductivity (it diffuses u)")
            } else {
                None
            };
            if let Some(what) = clash {
                return Err(CoreError::Invalid(format!(
                    "equation of state {}: pressure does not depend on u, so {what} cannot be used with it; choose other volumes or conductivity 0, or an ideal gas",
                    self.eos
                )));
            }
        }
        if let Some(stir) = &self.stirring {
            stir.validate()?;
        }
        if self.bucket == 0 {
            return Err(CoreError::Invalid("bucket size must be at least 1".into()));
        }
        Ok(())
    }

    /// The optional per-particle fields a run with this configuration
    /// needs.
    pub fn fields(&self) -> FieldSet {
        FieldSet {
            eos_ref: self.eos.needs_reference(),
            block: self.time_steps.on_time_line(),
            stirring: self.stirring.is_some(),
            ..self.scheme.fields(self.gravity.is_some())
        }
    }
}
