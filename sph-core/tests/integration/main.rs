//! sph-core's integration tests, one binary: each module was a binary of
//! its own, and each compiled the solver again (optimised builds share no
//! generic code between crates); one binary compiles and links it once.

mod av_switch;
mod barotropic;
mod bins;
mod block_steps;
mod common;
mod pair_masks;
mod particles;
mod presets;
mod stages;
mod stirred;
mod stirring;
mod timestep;
mod volume_elements;
