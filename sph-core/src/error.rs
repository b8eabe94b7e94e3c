//! Errors of the SPH stages.

use sph_tree::TreeError;

/// A numerical failure or bad input, naming the particle (by its id) and
/// the step where it happened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CoreError {
    /// A quantity became NaN or infinite.
    #[error("step {step}: particle id {id} has a non-finite {field} ({value})")]
    NonFinite {
        /// Step number.
        step: u64,
        /// Particle id.
        id: u64,
        /// Which field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// Internal energy went negative even with the first-order fallback.
    #[error("step {step}: particle id {id} reached negative internal energy u = {u:e} (du/dt = {du:e}, dt = {dt:e})")]
    NegativeEnergy {
        /// Step number.
        step: u64,
        /// Particle id.
        id: u64,
        /// The would-be internal energy.
        u: f64,
        /// Its rate of change.
        du: f64,
        /// The time step.
        dt: f64,
    },
    /// The IAD matrix of a particle cannot be inverted.
    #[error("step {step}: IAD matrix of particle id {id} is singular (determinant {det:e}); too few or coplanar neighbours ({neighbors})")]
    SingularIad {
        /// Step number.
        step: u64,
        /// Particle id.
        id: u64,
        /// Determinant of the scaled matrix.
        det: f64,
        /// Neighbour count.
        neighbors: usize,
    },
    /// The smoothing-length iteration did not bring a neighbour count into range.
    #[error("step {step}: smoothing length of particle id {id} did not converge after {iterations} iterations: {count} neighbours, allowed {min}..={max} (h = {h:e})")]
    HIteration {
        /// Step number.
        step: u64,
        /// Particle id.
        id: u64,
        /// Iterations done.
        iterations: usize,
        /// Last neighbour count.
        count: usize,
        /// Lowest acceptable count.
        min: usize,
        /// Highest acceptable count.
        max: usize,
        /// Last smoothing length.
        h: f64,
    },
    /// Arrays of different lengths, or a bad parameter.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// Failure of the domain decomposition or its communication.
    #[error(transparent)]
    Domain(#[from] sph_domain::DomainError),
    /// Failure in the tree crate.
    #[error(transparent)]
    Tree(#[from] TreeError),
    /// Bad self-gravity parameters (at set-up).
    #[error("self-gravity: {0}")]
    GravitySetup(#[source] sph_gravity::GravityError),
    /// Self-gravity failed during a step.
    #[error("step {step}: self-gravity: {source}")]
    Gravity {
        /// Step number.
        step: u64,
        /// The cause.
        #[source]
        source: sph_gravity::GravityError,
    },
}
