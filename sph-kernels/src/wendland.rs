//! Wendland C2, C4 and C6 kernels (Wendland 1995; Dehnen & Aly 2012), support `2h`.
//!
//! With `q = v/2` the standard polynomials are used unchanged; `dw/dv = 1/2 dw/dq`.

use std::f64::consts::PI;

use crate::kernel::Kernel;

/// Wendland C2, support `2h`: `w = (1-q)^4 (1 + 4q)`, `q = v/2`, `K = 21/(16 pi)`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WendlandC2;

/// Wendland C4, support `2h`: `w = (1-q)^6 (1 + 6q + 35/3 q^2)`, `q = v/2`,
/// `K = 495/(256 pi)`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WendlandC4;

/// Wendland C6, support `2h`: `w = (1-q)^8 (1 + 8q + 25q^2 + 32q^3)`, `q = v/2`,
/// `K = 1365/(512 pi)`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WendlandC6;

impl WendlandC2 {
    /// The Wendland C2 kernel.
    pub fn new() -> Self {
        Self
    }
}

impl WendlandC4 {
    /// The Wendland C4 kernel.
    pub fn new() -> Self {
        Self
    }
}

impl WendlandC6 {
    /// The Wendland C6 kernel.
    pub fn new() -> Self {
        Self
    }
}

/// `(q, 1 - q)` for `v` inside the support, `None` outside (and for NaN).
#[inline]
fn q_and_one_minus_q(v: f64) -> Option<(f64, f64)> {
    (v < 2.0).then(|| {
        let q = 0.5 * v;
        (q, 1.0 - q)
    })
}

impl Kernel for WendlandC2 {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| t.powi(4) * (1.0 + 4.0 * q))
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        // dw/dq = -20 q (1-q)^3.
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| -10.0 * q * t.powi(3))
    }

    #[inline]
    fn norm(&self) -> f64 {
        21.0 / (16.0 * PI)
    }
}

impl Kernel for WendlandC4 {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| t.powi(6) * (1.0 + q * (6.0 + 35.0 / 3.0 * q)))
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        // dw/dq = -56/3 q (1-q)^5 (1 + 5q).
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| -28.0 / 3.0 * q * t.powi(5) * (1.0 + 5.0 * q))
    }

    #[inline]
    fn norm(&self) -> f64 {
        495.0 / (256.0 * PI)
    }
}

impl Kernel for WendlandC6 {
    #[inline]
    fn shape(&self, v: f64) -> f64 {
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| {
            t.powi(8) * (1.0 + q * (8.0 + q * (25.0 + 32.0 * q)))
        })
    }

    #[inline]
    fn shape_derivative(&self, v: f64) -> f64 {
        // dw/dq = -22 q (1-q)^7 (1 + 7q + 16q^2).
        q_and_one_minus_q(v).map_or(0.0, |(q, t)| {
            -11.0 * q * t.powi(7) * (1.0 + q * (7.0 + 16.0 * q))
        })
    }

    #[inline]
    fn norm(&self) -> f64 {
        1365.0 / (512.0 * PI)
    }
}
