//! Block-step states at times between sub-steps: what a snapshot at a
//! requested time holds.
//!
//! Between two kicks a particle moves as the drift of a sub-step moves it
//! (`hydro/block.rs`): its position by its share of the step's
//! displacement, `v + a dt`, `u + du dt`, density and smoothing length by
//! the density's rate. After a sub-step every particle is somewhere
//! inside its current step, so the state at any time of the sub-step just
//! taken follows from the current one by the same formulas, run back.

use super::block::{density_drift, drift_rate, h_drift};
use super::BlockRun;
use crate::timeline::{Bin, TimeLine};
use crate::{CoreError, Particles};
use sph_tree::BoundingBox;
use std::ops::Range;

/// The fields [`predict_field`] moves in time; the others (pressure,
/// accelerations, ...) are those of each particle's last evaluation.
pub const PREDICTED: [&str; 9] = ["x", "y", "z", "vx", "vy", "vz", "u", "rho", "h"];

/// Moves the owned particles' values of `field` (`values`, one per owned
/// particle, as the particles hold them at `t_now`) to `t_out`, a time of
/// the sub-step that ended at `t_now` (`t_out <= t_now`, no earlier than
/// any particle's current step start) of the block-step run at `run`.
/// Positions are wrapped into periodic boxes. Returns whether `field` is
/// one of [`PREDICTED`] (others are left as they are).
///
/// ```
/// use sph_core::hydro::predict_field;
/// use sph_core::{BlockRun, FieldSet, Particles};
/// use sph_tree::{Boundary, BoundingBox};
/// let mut p = Particles::new(1, FieldSet::default());
/// p.enable_block_steps(FieldSet::NONE);
/// // A step of 2^49 ticks of a line [0, 1]: 1/8; displacement 0.1 over it.
/// p.bin[0] = 49.0;
/// p.dx[0] = 0.1;
/// p.x[0] = 0.5;
/// p.vx[0] = 0.8;
/// p.ax[0] = 2.0;
/// let run = BlockRun { t_begin: 0.0, t_end: 1.0, dt_max_bin: 49, dt_max: 0.125, ramp_origin: f64::NEG_INFINITY, ti: 0, updates: 0, syncs: 0 };
/// let bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
/// let mut x = vec![p.x[0]];
/// assert!(predict_field(&p, 0..1, &bbox, &run, 0.25, 0.25 - 1.0 / 16.0, "x", &mut x).unwrap());
/// assert!((x[0] - 0.45).abs() < 1e-15); // half the step back: half of dX
/// let mut vx = vec![p.vx[0]];
/// predict_field(&p, 0..1, &bbox, &run, 0.25, 0.25 - 1.0 / 16.0, "vx", &mut vx).unwrap();
/// assert!((vx[0] - (0.8 - 2.0 / 16.0)).abs() < 1e-15);
/// ```
///
/// # Errors
/// Particles without bins (not built for block steps), `values` of
/// another length than `owned`, or a `t_out` after `t_now`.
#[allow(clippy::too_many_arguments)]
pub fn predict_field(
    p: &Particles,
    owned: Range<usize>,
    bbox: &BoundingBox,
    run: &BlockRun,
    t_now: f64,
    t_out: f64,
    field: &str,
    values: &mut [f64],
) -> Result<bool, CoreError> {
    if !PREDICTED.contains(&field) {
        return Ok(false);
    }
    if p.bin.len() != p.len() {
        return Err(CoreError::Invalid(
            "predicting a block-step state needs the particles' bins (FieldSet::block)".into(),
        ));
    }
    if values.len() != owned.len() {
        return Err(CoreError::Invalid(format!(
            "{} values given for {} particles",
            values.len(),
            owned.len()
        )));
    }
    // `t_out` may exceed `t_now` by rounding only (an output time asked
    // for at the end of the step): it is then `t_now`.
    let latest = t_now + 1e-12 * t_now.abs() + f64::MIN_POSITIVE;
    if t_out.is_nan() || t_out > latest {
        return Err(CoreError::Invalid(format!(
            "a state at t = {t_out} cannot be predicted from t = {t_now}: only back within the last sub-step"
        )));
    }
    let dt = (t_out - t_now).min(0.0);
    if dt == 0.0 {
        return Ok(true);
    }
    let line = TimeLine::with_top_bin(run.t_begin, run.t_end, Bin(run.dt_max_bin))?;
    let axis = |f: &str| ["x", "y", "z"].iter().position(|&a| a == f);
    let dx = [&p.dx, &p.dy, &p.dz];
    let a = [&p.ax, &p.ay, &p.az];
    for (k, v) in values.iter_mut().enumerate() {
        let i = owned.start + k;
        *v = match field {
            "vx" | "vy" | "vz" => *v + a[axis(&field[1..]).expect("an axis")][i] * dt,
            "u" => *v + p.du[i] * dt,
            "rho" | "h" => {
                let step = line.dt(Bin(p.bin[i] as u8));
                let r = drift_rate(p.dlnrho[i], step);
                *v * if field == "rho" {
                    density_drift(r, dt)
                } else {
                    h_drift(r, dt)
                }
            }
            _ => {
                let c = axis(field).expect("a position");
                let step = line.dt(Bin(p.bin[i] as u8));
                let mut pos = [p.x[i], p.y[i], p.z[i]];
                pos[c] = *v + dx[c][i] * (dt / step);
                bbox.wrap(pos)[c]
            }
        };
    }
    Ok(true)
}
