//! The stirring acceleration at particle positions, `O(N x entries)`.
//!
//! Every wave number is an integer in `[-3, 3]`, so a particle needs one
//! `sin_cos` per axis: `e_x = exp(i k1 x)` with `k1 = 2 pi / L`, its powers
//! by complex products (negative powers are conjugates), then per entry the
//! phasor `e_x^nx e_y^ny e_z^nz` (the `x y` products shared within a
//! triple) and two multiply-adds per component, against the C++ code's six
//! libm calls per entry.
//!
//! Positions are used raw, not shifted to the box corner: the field is
//! then the C++ code's function of position for the same phases (a shift
//! by the corner `-L/2` would flip the sign of the odd modes; the field is
//! periodic either way).
//!
//! The same generic code runs on one particle (`f64`) and on [`LANES`]
//! particles ([`F64s`]): element-wise IEEE operations, multiply-adds fused
//! on both or on neither (as the build's target features say), `sin_cos`
//! from one lane polynomial, and the entries summed in order. Each lane is
//! therefore bit for bit the scalar result, and the bits depend on neither
//! lanes nor threads.

use super::modes::ModeSet;
use super::ou::Amplitudes;
use rayon::prelude::*;
use sph_kernels::{F64s, LANES};
use std::ops::{Add, Mul, Sub};

/// Particles per rayon task.
pub const CHUNK: usize = 1024;

/// The arithmetic the field needs, on one value or on lanes.
trait Value: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    fn splat(v: f64) -> Self;
    /// `self b + c`, fused where the build targets FMA (on both types).
    fn mul_add(self, b: Self, c: Self) -> Self;
}

impl Value for f64 {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        sph_kernels::lanes::mul_add(self, b, c)
    }
}

impl Value for F64s {
    #[inline(always)]
    fn splat(v: f64) -> Self {
        F64s::splat(v)
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        F64s::mul_add(self, b, c)
    }
}

#[derive(Clone, Copy)]
struct Complex<T> {
    re: T,
    im: T,
}

impl<T: Value> Complex<T> {
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Complex {
            re: self.re * o.re - self.im * o.im,
            im: self.re.mul_add(o.im, self.im * o.re),
        }
    }

    #[inline(always)]
    fn conj(self) -> Self {
        Complex {
            re: self.re,
            im: T::splat(0.0) - self.im,
        }
    }
}

/// `e^p` for `p = -3..=3` at index `p + 3`, from `e = cos + i sin`.
#[inline(always)]
fn powers<T: Value>(sin: T, cos: T) -> [Complex<T>; 7] {
    let one = Complex {
        re: T::splat(1.0),
        im: T::splat(0.0),
    };
    let e1 = Complex { re: cos, im: sin };
    let e2 = e1.mul(e1);
    let e3 = e2.mul(e1);
    [e3.conj(), e2.conj(), e1.conj(), one, e1, e2, e3]
}

/// The sum over entries, in entry order, of `re cos(k.x) - im sin(k.x)`
/// per component, from the per-axis power tables.
#[inline(always)]
fn sum_entries<T: Value>(modes: &ModeSet, amps: &Amplitudes, p: &[[Complex<T>; 7]; 3]) -> [T; 3] {
    // e_x^nx e_y^ny for nx in 0..=3: shared by the entries of a triple; the
    // same products in the same order as without the table.
    let xy: [[Complex<T>; 7]; 4] = std::array::from_fn(|nx| p[1].map(|ey| p[0][nx + 3].mul(ey)));
    let mut acc = [T::splat(0.0); 3];
    let [rx, ry, rz] = &amps.re;
    let [ix, iy, iz] = &amps.im;
    let rows = modes
        .n
        .iter()
        .zip(rx)
        .zip(ry)
        .zip(rz)
        .zip(ix)
        .zip(iy)
        .zip(iz);
    for ((((((n, &rx), &ry), &rz), &ix), &iy), &iz) in rows {
        let ph = xy[n[0] as usize][(n[1] + 3) as usize].mul(p[2][(n[2] + 3) as usize]);
        // re cos - im sin as two multiply-adds into the sum.
        for (a, (r, i)) in acc.iter_mut().zip([(rx, ix), (ry, iy), (rz, iz)]) {
            *a = ph.im.mul_add(T::splat(-i), ph.re.mul_add(T::splat(r), *a));
        }
    }
    acc
}

/// The acceleration at one position: the reference of [`accelerate`].
/// `k1 = 2 pi / L`.
pub fn accelerate_one(modes: &ModeSet, amps: &Amplitudes, k1: f64, pos: [f64; 3]) -> [f64; 3] {
    let p = pos.map(|c| {
        let (s, c) = sin_cos([c * k1; LANES]);
        powers(s[0], c[0])
    });
    sum_entries(modes, amps, &p)
}

/// `(sin, cos)` per lane by `wide`'s polynomial (libm's separate `sin` and
/// `cos` took 40% of the time); the scalar path takes lane 0 of it, so both
/// paths see the same bits.
#[inline(always)]
fn sin_cos(theta: [f64; LANES]) -> ([f64; LANES], [f64; LANES]) {
    let (s, c) = wide::f64x8::new(theta).sin_cos();
    (s.to_array(), c.to_array())
}

/// Writes the acceleration at `(x[i], y[i], z[i])` into `(ax[i], ay[i],
/// az[i])` for every `i`, in parallel over chunks of [`CHUNK`] particles,
/// [`LANES`] particles at a time; equal bit for bit to [`accelerate_one`].
///
/// # Panics
///
/// If the six slices do not have one length.
pub fn accelerate(
    modes: &ModeSet,
    amps: &Amplitudes,
    k1: f64,
    x: &[f64],
    y: &[f64],
    z: &[f64],
    ax: &mut [f64],
    ay: &mut [f64],
    az: &mut [f64],
) {
    let n = x.len();
    assert!(
        [y.len(), z.len(), ax.len(), ay.len(), az.len()]
            .iter()
            .all(|&l| l == n),
        "stirring: positions and accelerations differ in length"
    );
    let pos = [x, y, z];
    ax.par_chunks_mut(CHUNK)
        .zip(ay.par_chunks_mut(CHUNK))
        .zip(az.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(chunk, ((ax, ay), az))| {
            let start = chunk * CHUNK;
            for first in (0..ax.len()).step_by(LANES) {
                let valid = LANES.min(ax.len() - first);
                let p =
                    std::array::from_fn(|axis| lane_powers(pos[axis], start + first, valid, k1));
                let acc = sum_entries(modes, amps, &p);
                let range = first..first + valid;
                acc[0].store(&mut ax[range.clone()]);
                acc[1].store(&mut ay[range.clone()]);
                acc[2].store(&mut az[range]);
            }
        });
}

/// The power table of one axis for the lanes of `valid` particles from
/// `first` (padding lanes repeat the last particle).
#[inline(always)]
fn lane_powers(c: &[f64], first: usize, valid: usize, k1: f64) -> [Complex<F64s>; 7] {
    let (sin, cos) = sin_cos(std::array::from_fn(|l| c[first + l.min(valid - 1)] * k1));
    powers(F64s::from_array(sin), F64s::from_array(cos))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_sin_cos_agrees_with_libm() {
        // Arguments up to 100 (particles up to 16 boxes away from the
        // origin): within a few ulps of 1.
        let mut worst: f64 = 0.0;
        for i in 0..20_000 {
            let theta: [f64; LANES] =
                std::array::from_fn(|l| (i * LANES + l) as f64 * 1.25e-3 - 100.0);
            let (s, c) = sin_cos(theta);
            for l in 0..LANES {
                worst = worst
                    .max((s[l] - theta[l].sin()).abs())
                    .max((c[l] - theta[l].cos()).abs());
            }
        }
        eprintln!("lane sin_cos against libm: worst difference {worst:.2e}");
        assert!(worst < 1e-15, "worst difference {worst:e}");
    }
}
