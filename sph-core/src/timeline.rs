//! The integer time line of block (individual) time steps.
//!
//! A run's span `[t_begin, t_end]` is cut into `2^52` ticks of
//! `time_base = (t_end - t_begin) / 2^52`. A particle in [`Bin`] `b` takes
//! steps of `2^b` ticks that start on multiples of `2^b`: the steps of all
//! bins nest, a particle is active at tick `ti` when `ti` is a multiple of
//! its step, and every particle is at a step boundary (a synchronisation
//! point) at the multiples of the largest step in use. Every tick count
//! below `2^53` is an exact `f64`, so a step's length is `ticks * time_base`
//! with one rounding, whichever way the run reached it; decisions are made
//! on integers and do not depend on the order of operations, the threads or
//! the ranks.
//!
//! [`TimeLine::new_bin`] turns a particle's time-step criteria into its
//! bin: the largest power-of-two step they allow, capped by the longest
//! step, by its neighbours' bins (the time-step limiter: at most `2^delta`
//! times a neighbour's step), by doubling at most per step, and by where
//! the step can start. [`step_begin`] gives the step of a bin that holds a
//! tick, which is where a particle woken by the limiter restarts.
//!
//! ```
//! use sph_core::timeline::{is_active, Bin, BinLimit, TimeLine};
//!
//! let line = TimeLine::new(0.0, 1.0, 0.25).unwrap();
//! // 0.01 of the span: the largest power-of-two step below it is 2^-7.
//! let (bin, why) = line.new_bin(0.01, None, 0, None, 2).unwrap();
//! assert_eq!((line.dt(bin), why), (1.0 / 128.0, BinLimit::Criteria));
//! // A particle whose neighbour is 3 bins lower is held 2 bins above it.
//! let (held, why) = line.new_bin(0.01, None, 0, Some(Bin(bin.0 - 3)), 2).unwrap();
//! assert_eq!((held, why), (Bin(bin.0 - 1), BinLimit::Neighbours));
//! assert!(is_active(3 * held.ticks(), held) && !is_active(held.ticks() / 2, held));
//! ```

use crate::CoreError;

/// A position on the time line, in ticks from its start.
pub type Ticks = u64;

/// The largest bin: one step over the whole span.
pub const MAX_BIN: u8 = 52;

/// The ticks of the whole span, `2^MAX_BIN`.
pub const LINE: Ticks = 1 << MAX_BIN;

/// A time bin: steps of `2^b` ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Bin(pub u8);

impl Bin {
    /// The step of this bin, in ticks.
    pub fn ticks(self) -> Ticks {
        1 << self.0
    }
}

/// What set a particle's new bin ([`TimeLine::new_bin`]), the first of
/// these caps that bound it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinLimit {
    /// The particle's own criteria (the step asked for).
    Criteria,
    /// The longest step of the run.
    DtMax,
    /// The limiter: at most `2^delta` times a neighbour's step.
    Neighbours,
    /// At most double the particle's previous step.
    Growth,
    /// A step can only start on a multiple of its length.
    Alignment,
}

/// The time line of one run: its span in ticks and its longest step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeLine {
    t_begin: f64,
    t_end: f64,
    time_base: f64,
    dt_max_bin: Bin,
}

impl TimeLine {
    /// The line over `[t_begin, t_end]` with steps no longer than `dt_max`
    /// (rounded down to a power-of-two number of ticks; at most the span).
    ///
    /// # Errors
    /// [`CoreError::Invalid`] unless the times are finite with
    /// `t_end > t_begin`, and `dt_max` is at least one tick.
    pub fn new(t_begin: f64, t_end: f64, dt_max: f64) -> Result<Self, CoreError> {
        if !(t_begin.is_finite() && t_end.is_finite() && t_end > t_begin) {
            return Err(CoreError::Invalid(format!(
                "time line [{t_begin}, {t_end}]: the end must be a finite time after the start"
            )));
        }
        let time_base = (t_end - t_begin) / LINE as f64;
        if time_base <= 0.0 {
            return Err(CoreError::Invalid(format!(
                "time line [{t_begin}, {t_end}]: the span is too short for 2^{MAX_BIN} ticks"
            )));
        }
        let mut line = TimeLine {
            t_begin,
            t_end,
            time_base,
            dt_max_bin: Bin(MAX_BIN),
        };
        line.dt_max_bin = line.floor_bin(dt_max).ok_or_else(|| {
            CoreError::Invalid(format!(
                "longest step {dt_max}: must be at least one tick ({time_base:e}) of the time line [{t_begin}, {t_end}]"
            ))
        })?;
        Ok(line)
    }

    /// The line over `[t_begin, t_end]` whose longest step is `2^top`
    /// ticks: the line [`new`](Self::new) made, rebuilt from its parts
    /// (a checkpoint's), with the same bits.
    ///
    /// ```
    /// use sph_core::timeline::TimeLine;
    /// let line = TimeLine::new(0.0, 0.05, 0.05 / 8.0).unwrap();
    /// let again = TimeLine::with_top_bin(0.0, 0.05, line.dt_max_bin()).unwrap();
    /// assert_eq!(line, again);
    /// ```
    ///
    /// # Errors
    /// As [`new`](Self::new), and a bin above [`MAX_BIN`].
    pub fn with_top_bin(t_begin: f64, t_end: f64, top: Bin) -> Result<Self, CoreError> {
        if top.0 > MAX_BIN {
            return Err(CoreError::Invalid(format!(
                "time line: longest bin {} is above {MAX_BIN}",
                top.0
            )));
        }
        let mut line = Self::new(t_begin, t_end, t_end - t_begin)?;
        line.dt_max_bin = top;
        Ok(line)
    }

    /// The length of one tick.
    pub fn time_base(&self) -> f64 {
        self.time_base
    }

    /// The longest bin of the run.
    pub fn dt_max_bin(&self) -> Bin {
        self.dt_max_bin
    }

    /// The time at tick `ti` (`t_end` exactly at [`LINE`]).
    pub fn time(&self, ti: Ticks) -> f64 {
        if ti >= LINE {
            self.t_end
        } else {
            self.t_begin + ti as f64 * self.time_base
        }
    }

    /// The length of a step of `bin`.
    pub fn dt(&self, bin: Bin) -> f64 {
        bin.ticks() as f64 * self.time_base
    }

    /// Whole ticks in `dt` (rounded down; NaN and negative give 0; at most
    /// [`LINE`]).
    pub fn ticks(&self, dt: f64) -> Ticks {
        let t = (dt / self.time_base).floor();
        if t >= LINE as f64 {
            LINE
        } else if t >= 1.0 {
            t as Ticks
        } else {
            0
        }
    }

    /// The largest bin whose step is at most `dt` (at most [`MAX_BIN`]), or
    /// `None` below one tick.
    /// The bin of the longest step of this line no longer than `dt`,
    /// within the line's bins (0 for a step below one tick): where a step
    /// of another line falls on this one.
    pub fn bin_of_dt(&self, dt: f64) -> Bin {
        self.floor_bin(dt)
            .map_or(Bin(0), |b| b.min(self.dt_max_bin))
    }

    fn floor_bin(&self, dt: f64) -> Option<Bin> {
        let t = self.ticks(dt);
        (t > 0).then(|| Bin((Ticks::BITS - 1 - t.leading_zeros()) as u8))
    }

    /// The bin of a particle starting a step at tick `ti` whose criteria ask
    /// for at most `dt`: the largest power-of-two step no longer than `dt`,
    /// then capped in turn by the longest step, by `min_neighbour + delta`
    /// (the limiter; `None` without neighbours), by `old + 1` (the bin of
    /// its last step, `None` for a first step) and by the largest step that
    /// can start at `ti` (`ti` a multiple of it). Returns the bin and the
    /// first cap that bound it.
    ///
    /// # Errors
    /// [`CoreError::Invalid`] naming `dt` when it is shorter than one tick.
    pub fn new_bin(
        &self,
        dt: f64,
        old: Option<Bin>,
        ti: Ticks,
        min_neighbour: Option<Bin>,
        delta: u8,
    ) -> Result<(Bin, BinLimit), CoreError> {
        let mut bin = self.floor_bin(dt).ok_or_else(|| {
            CoreError::Invalid(format!(
                "time step {dt:e} is shorter than one tick ({:e}) of the time line",
                self.time_base
            ))
        })?;
        let mut limit = BinLimit::Criteria;
        let caps = [
            (Some(self.dt_max_bin), BinLimit::DtMax),
            (
                min_neighbour.map(|b| Bin(b.0.saturating_add(delta).min(MAX_BIN))),
                BinLimit::Neighbours,
            ),
            (old.map(|b| Bin((b.0 + 1).min(MAX_BIN))), BinLimit::Growth),
            (Some(max_active_bin(ti)), BinLimit::Alignment),
        ];
        for (cap, why) in caps {
            if let Some(cap) = cap.filter(|&c| c < bin) {
                bin = cap;
                limit = why;
            }
        }
        Ok((bin, limit))
    }
}

/// Whether a particle of `bin` is at a step boundary at tick `ti`.
pub fn is_active(ti: Ticks, bin: Bin) -> bool {
    ti.is_multiple_of(bin.ticks())
}

/// The largest bin active at tick `ti` ([`MAX_BIN`] at 0).
pub fn max_active_bin(ti: Ticks) -> Bin {
    Bin(ti.trailing_zeros().min(MAX_BIN as u32) as u8)
}

/// The start of the step of `bin` that holds tick `ti` (a step holds its
/// start, not its end): where a particle moved down to `bin` at `ti` (woken
/// by the limiter) restarts.
pub fn step_begin(ti: Ticks, bin: Bin) -> Ticks {
    ti - ti % bin.ticks()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_line_spans_exactly() {
        let line = TimeLine::new(0.0, 0.05, 0.05).unwrap();
        assert_eq!(line.time(LINE), 0.05);
        assert_eq!(line.time(0), 0.0);
        assert_eq!(line.dt(Bin(MAX_BIN)), 0.05);
        assert_eq!(line.dt_max_bin(), Bin(MAX_BIN));
        // Half the span is bin 51, exactly.
        assert_eq!(line.time(LINE / 2), 0.025);
        let offset = TimeLine::new(0.3, 1.0, 1.0).unwrap();
        assert_eq!(offset.time(LINE), 1.0);
    }

    #[test]
    fn bad_lines_are_refused_by_name() {
        for (a, b, d) in [
            (0.0, 0.0, 1.0),
            (1.0, 0.0, 1.0),
            (0.0, f64::NAN, 1.0),
            (0.0, f64::INFINITY, 1.0),
        ] {
            let e = TimeLine::new(a, b, d).unwrap_err().to_string();
            assert!(e.contains("time line"), "{e}");
        }
        let e = TimeLine::new(0.0, 1.0, 0.0).unwrap_err().to_string();
        assert!(e.contains("longest step 0"), "{e}");
        let line = TimeLine::new(0.0, 1.0, 1.0).unwrap();
        let e = line.new_bin(1e-300, None, 0, None, 2).unwrap_err();
        assert!(e.to_string().contains("shorter than one tick"), "{e}");
        assert!(line.new_bin(f64::NAN, None, 0, None, 2).is_err());
    }

    #[test]
    fn the_longest_step_caps_every_bin() {
        let line = TimeLine::new(0.0, 1.0, 0.3).unwrap();
        // 0.3 rounds down to 0.25: bin 50.
        assert_eq!(line.dt_max_bin(), Bin(50));
        assert_eq!(
            line.new_bin(10.0, None, 0, None, 2).unwrap(),
            (Bin(50), BinLimit::DtMax)
        );
    }

    #[test]
    fn growth_and_alignment_hold_a_particle_back() {
        let line = TimeLine::new(0.0, 1.0, 1.0).unwrap();
        // At tick 2^10 a particle of bin 10 may double only if 2^11 divides
        // the tick: it does not, so it keeps bin 10.
        let ti = 1 << 10;
        assert_eq!(
            line.new_bin(1.0, Some(Bin(10)), ti, None, 2).unwrap(),
            (Bin(10), BinLimit::Alignment)
        );
        // At tick 2^11 it doubles, no more.
        assert_eq!(
            line.new_bin(1.0, Some(Bin(10)), 1 << 11, None, 2).unwrap(),
            (Bin(11), BinLimit::Growth)
        );
        // Shorter steps are always allowed.
        assert_eq!(
            line.new_bin(line.dt(Bin(3)), Some(Bin(10)), ti, None, 2)
                .unwrap(),
            (Bin(3), BinLimit::Criteria)
        );
    }

    fn line() -> impl Strategy<Value = TimeLine> {
        (0.0f64..10.0, 1e-6f64..100.0, 1e-3f64..=1.0).prop_map(|(t0, span, frac)| {
            TimeLine::new(t0, t0 + span, span * frac).expect("a valid line")
        })
    }

    proptest! {
        /// The new bin is the largest that every cap allows: no longer
        /// than the criteria, the longest step, the neighbours' bins plus
        /// delta, double the old step, and starting on a multiple of its
        /// length at ti.
        #[test]
        fn new_bins_obey_every_cap_and_are_the_largest_that_do(
            line in line(),
            frac in 1e-12f64..2.0,
            old in proptest::option::of(0u8..=MAX_BIN),
            ngb in proptest::option::of(0u8..=MAX_BIN),
            delta in 0u8..4,
            ti_raw in 0u64..LINE,
        ) {
            let dt = frac * line.dt(Bin(MAX_BIN));
            // A particle of bin old is active at ti: ti a multiple of its step.
            let ti = match old {
                Some(b) => step_begin(ti_raw, Bin(b)),
                None => ti_raw,
            };
            let Ok((bin, _)) = line.new_bin(dt, old.map(Bin), ti, ngb.map(Bin), delta) else {
                prop_assert!(line.ticks(dt) == 0);
                return Ok(());
            };
            let ok = |b: Bin| {
                line.dt(b) <= dt
                    && b <= line.dt_max_bin()
                    && ngb.is_none_or(|n| b.0 as u32 <= n as u32 + delta as u32)
                    && old.is_none_or(|o| b.0 as u32 <= o as u32 + 1)
                    && is_active(ti, b)
            };
            prop_assert!(ok(bin), "bin {bin:?} breaks a cap");
            if bin.0 < MAX_BIN {
                prop_assert!(!ok(Bin(bin.0 + 1)), "bin {bin:?} is not the largest");
            }
        }

        /// A step moved down to a shorter bin at ti starts at or before ti
        /// on a multiple of its length, holds ti, and ends no later than
        /// the old step it interrupts: steps nest.
        #[test]
        fn woken_steps_nest_in_the_old_one(old in 1u8..=MAX_BIN, down in 1u8..=MAX_BIN, ti in 0u64..LINE) {
            let new = Bin(old.saturating_sub(down));
            let old = Bin(old);
            let (b_old, b_new) = (step_begin(ti, old), step_begin(ti, new));
            prop_assert!(b_new <= ti && ti < b_new + new.ticks());
            prop_assert!(is_active(b_new, new));
            prop_assert!(b_old <= b_new);
            prop_assert!(b_new + new.ticks() <= b_old + old.ticks());
        }

        /// A tick is active for exactly the bins up to its largest active
        /// bin.
        #[test]
        fn activity_is_the_trailing_zeros(ti in 0u64..=LINE, b in 0u8..=MAX_BIN) {
            prop_assert_eq!(is_active(ti, Bin(b)), Bin(b) <= max_active_bin(ti));
        }

        /// Step lengths are exact: a bin's step is twice the one below,
        /// and times of ticks are increasing.
        #[test]
        fn steps_double_and_times_increase(line in line(), b in 0u8..MAX_BIN, ti in 0u64..LINE - 1) {
            prop_assert_eq!(line.dt(Bin(b + 1)), 2.0 * line.dt(Bin(b)));
            prop_assert!(line.time(ti + 1) >= line.time(ti));
        }

        /// Particles with equal criteria take equal bins: a uniform state
        /// is one bin.
        #[test]
        fn equal_criteria_give_one_bin(line in line(), frac in 1e-9f64..1.0) {
            let dt = frac * line.dt(Bin(MAX_BIN));
            let a = line.new_bin(dt, None, 0, None, 2).unwrap();
            let b = line.new_bin(dt, None, 0, Some(a.0), 2).unwrap();
            prop_assert_eq!(a.0, b.0);
        }
    }
}
