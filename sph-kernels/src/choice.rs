//! Choosing a built-in kernel by name (command lines, config files).

use std::fmt;
use std::str::FromStr;

use crate::{
    CubicSpline, FastKernel, Kernel, KernelError, Sinc, Tabulated, WendlandC2, WendlandC4,
    WendlandC6,
};

/// A built-in kernel, as named on a command line.
///
/// Parses (case-insensitively, surrounding blanks ignored) `sinc` (= `sinc:6`),
/// `sinc:<n>` for any real `n` in `[1, 1000]` (e.g. `sinc:5.5`), `m4` or
/// `cubic-spline`, `wendland-c2`, `wendland-c4`, `wendland-c6`.
/// [`Display`](fmt::Display) writes a string that parses back to the same value.
///
/// ```
/// use sph_kernels::KernelChoice;
/// let choice: KernelChoice = "sinc:5.5".parse()?;
/// assert_eq!(choice, KernelChoice::Sinc(5.5));
/// assert_eq!(choice.to_string(), "sinc:5.5");
/// assert_eq!("m4".parse::<KernelChoice>()?, KernelChoice::CubicSpline);
/// assert!("gauss".parse::<KernelChoice>().unwrap_err().to_string().contains("gauss"));
/// # Ok::<(), sph_kernels::KernelError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KernelChoice {
    /// [`Sinc`] with the given exponent.
    Sinc(f64),
    /// [`CubicSpline`] (M4).
    CubicSpline,
    /// [`WendlandC2`].
    WendlandC2,
    /// [`WendlandC4`].
    WendlandC4,
    /// [`WendlandC6`].
    WendlandC6,
}

impl KernelChoice {
    /// Accepted spellings, for `--help` texts and error messages.
    pub fn names() -> &'static [&'static str] {
        &[
            "sinc",
            "sinc:<n>",
            "m4",
            "cubic-spline",
            "wendland-c2",
            "wendland-c4",
            "wendland-c6",
        ]
    }

    /// The exact (analytic) kernel.
    ///
    /// # Errors
    /// [`KernelError::SincExponent`] for a `Sinc(n)` with `n` out of range.
    pub fn exact(&self) -> Result<Box<dyn Kernel>, KernelError> {
        Ok(match *self {
            KernelChoice::Sinc(n) => Box::new(Sinc::new(n)?),
            KernelChoice::CubicSpline => Box::new(CubicSpline),
            KernelChoice::WendlandC2 => Box::new(WendlandC2),
            KernelChoice::WendlandC4 => Box::new(WendlandC4),
            KernelChoice::WendlandC6 => Box::new(WendlandC6),
        })
    }

    /// The kernel as a lookup table of `points` nodes
    /// (usually [`Tabulated::DEFAULT_POINTS`]).
    ///
    /// # Errors
    /// As [`exact`](Self::exact) and [`Tabulated::new`].
    pub fn tabulate(&self, points: usize) -> Result<Tabulated, KernelError> {
        Tabulated::new(&self.exact()?, points)
    }

    /// The kernel in the form the solver evaluates it: a polynomial where
    /// one is faithful, else the table ([`FastKernel::new`]).
    ///
    /// # Errors
    /// As [`exact`](Self::exact) and [`FastKernel::new`].
    pub fn fast(&self) -> Result<FastKernel, KernelError> {
        FastKernel::new(&self.exact()?)
    }
}

impl Default for KernelChoice {
    /// `sinc:6`, the SPH-EXA default.
    fn default() -> Self {
        KernelChoice::Sinc(Sinc::DEFAULT_EXPONENT)
    }
}

impl fmt::Display for KernelChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            // `{}` on f64 prints the shortest string that parses back exactly.
            KernelChoice::Sinc(n) => write!(f, "sinc:{n}"),
            KernelChoice::CubicSpline => f.write_str("cubic-spline"),
            KernelChoice::WendlandC2 => f.write_str("wendland-c2"),
            KernelChoice::WendlandC4 => f.write_str("wendland-c4"),
            KernelChoice::WendlandC6 => f.write_str("wendland-c6"),
        }
    }
}

impl FromStr for KernelChoice {
    type Err = KernelError;

    fn from_str(input: &str) -> Result<Self, Self::Err> {
        let name = input.trim().to_ascii_lowercase();
        if let Some(text) = name.strip_prefix("sinc:") {
            let n: f64 = text
                .trim()
                .parse()
                .map_err(|source| KernelError::BadSincNumber {
                    text: text.to_owned(),
                    input: input.to_owned(),
                    source,
                })?;
            // Validate now so a bad command line fails at parse time.
            Sinc::check_exponent(n)?;
            return Ok(KernelChoice::Sinc(n));
        }
        match name.as_str() {
            "sinc" => Ok(KernelChoice::default()),
            "m4" | "cubic-spline" => Ok(KernelChoice::CubicSpline),
            "wendland-c2" => Ok(KernelChoice::WendlandC2),
            "wendland-c4" => Ok(KernelChoice::WendlandC4),
            "wendland-c6" => Ok(KernelChoice::WendlandC6),
            _ => Err(KernelError::UnknownKernel {
                name: input.to_owned(),
                allowed: Self::names().join(", "),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_name_parses() {
        for name in KernelChoice::names() {
            let name = name.replace("<n>", "4.25");
            let choice: KernelChoice = name.parse().unwrap();
            assert_eq!(choice.to_string().parse::<KernelChoice>().unwrap(), choice);
            let table = choice.tabulate(1000).unwrap();
            assert_eq!(table.norm(), choice.exact().unwrap().norm());
        }
    }

    #[test]
    fn spellings() {
        assert_eq!(
            "sinc".parse::<KernelChoice>().unwrap(),
            KernelChoice::Sinc(6.0)
        );
        assert_eq!(
            " SINC:6 ".parse::<KernelChoice>().unwrap(),
            KernelChoice::Sinc(6.0)
        );
        assert_eq!(
            "sinc:5.5".parse::<KernelChoice>().unwrap(),
            KernelChoice::Sinc(5.5)
        );
        assert_eq!(
            "Cubic-Spline".parse::<KernelChoice>().unwrap(),
            KernelChoice::CubicSpline
        );
        assert_eq!(
            "wendland-c6".parse::<KernelChoice>().unwrap(),
            KernelChoice::WendlandC6
        );
        assert_eq!(KernelChoice::default().to_string(), "sinc:6");
    }

    #[test]
    fn unknown_name_is_named_and_alternatives_listed() {
        let msg = "gaussian".parse::<KernelChoice>().unwrap_err().to_string();
        assert!(msg.contains("\"gaussian\""), "{msg}");
        for name in KernelChoice::names() {
            assert!(msg.contains(name), "{msg}");
        }
        let msg = "".parse::<KernelChoice>().unwrap_err().to_string();
        assert!(msg.contains("unknown kernel \"\""), "{msg}");
    }

    #[test]
    fn bad_sinc_number_is_named() {
        for bad in ["sinc:abc", "sinc:", "sinc:6x", "sinc:1,5"] {
            let err = bad.parse::<KernelChoice>().unwrap_err();
            assert!(
                matches!(err, KernelError::BadSincNumber { .. }),
                "{bad}: {err}"
            );
            let msg = err.to_string();
            let text = bad.strip_prefix("sinc:").unwrap();
            assert!(
                msg.contains(&format!("\"{text}\"")) && msg.contains(bad),
                "{msg}"
            );
        }
    }

    #[test]
    fn sinc_exponent_out_of_range_is_named() {
        for (bad, value) in [
            ("sinc:0.5", "0.5"),
            ("sinc:-2", "-2"),
            ("sinc:nan", "NaN"),
            ("sinc:inf", "inf"),
            ("sinc:2000", "2000"),
        ] {
            let err = bad.parse::<KernelChoice>().unwrap_err();
            assert!(
                matches!(err, KernelError::SincExponent { .. }),
                "{bad}: {err}"
            );
            let msg = err.to_string();
            assert!(
                msg.contains(&format!("n = {value}")) && msg.contains("1 <= n"),
                "{msg}"
            );
        }
        // Constructed directly, the check happens when the kernel is built.
        assert!(KernelChoice::Sinc(0.0).tabulate(100).is_err());
    }
}
