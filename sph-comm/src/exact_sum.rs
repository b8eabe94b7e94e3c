//! Reproducible, exactly rounded summation of `f64` values (see [`ExactSum`]).

use std::fmt;
use std::iter::Sum;
use std::ops::AddAssign;

use crate::{Communicator, ReduceOp};

/// Number of 32-bit limbs: 2098 bits for the finite `f64` range plus 64 bits
/// of headroom for up to `2^64` terms, rounded up to whole limbs.
pub const LIMBS: usize = 68;

/// Limbs plus the three counters (NaN, +inf, -inf) exchanged in all-reduces.
const WORDS: usize = LIMBS + 3;

const MASK: i64 = (1 << 32) - 1;

/// Additions allowed between normalisations. A normalised limb is below
/// `2^32`, every addition changes a limb by less than `2^32`, so after
/// `MAX_PENDING` additions limbs stay below `2^62`.
const MAX_PENDING: u64 = 1 << 30;

/// Exact, order-independent sum of `f64` values.
///
/// # Representation
/// Every finite `f64` is an integer multiple of `2^-1074` below `2^1024`, so
/// the exact sum of any finite set of them is an integer multiple of
/// `2^-1074` too. [`ExactSum`] keeps that integer in a fixed-point
/// superaccumulator of [`LIMBS`] signed 64-bit limbs, limb `i` weighing
/// `2^(32 i - 1074)`. Adding a value adds its 53-bit significand, shifted into
/// place, to at most three limbs (32 payload bits each), so the 32 spare bits
/// of every limb absorb about `2^30` additions before a carry pass
/// ("normalisation") is needed. Integer addition is associative and
/// commutative, so the accumulator — and therefore the final rounding —
/// does not depend on the order or grouping of the additions, on the number
/// of rayon threads, or on the number of MPI ranks.
///
/// The value is rounded once, at the end, to the nearest `f64` (ties to
/// even), exactly like a single IEEE addition would round the true sum.
/// Infinities and NaNs are counted separately and reproduce IEEE semantics
/// (`inf + -inf = NaN`); an exact sum of zero is `+0.0`.
///
/// # Example
/// ```
/// use sph_comm::ExactSum;
/// let mut s = ExactSum::new();
/// for x in [1e308, 1.0, -1e308] {
///     s.add(x);
/// }
/// assert_eq!(s.value(), 1.0);
/// // Merging partial sums (e.g. one per rayon thread) is exact as well.
/// let a: ExactSum = [0.1, 0.2].into_iter().collect();
/// let b: ExactSum = [0.3].into_iter().collect();
/// let mut ab = a.clone();
/// ab.merge(&b);
/// let c: ExactSum = [0.3, 0.1, 0.2].into_iter().collect();
/// assert_eq!(ab.value().to_bits(), c.value().to_bits());
/// ```
///
/// With rayon, `xs.par_iter().copied().sum::<ExactSum>()` works because
/// `ExactSum` implements `Sum<f64>` and `Sum<ExactSum>`.
#[derive(Clone)]
pub struct ExactSum {
    limbs: [i64; LIMBS],
    /// Additions since the last normalisation (bounds the limb magnitudes).
    pending: u64,
    nan: u64,
    pos_inf: u64,
    neg_inf: u64,
}

impl Default for ExactSum {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for ExactSum {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ExactSum")
            .field("value", &self.value())
            .finish_non_exhaustive()
    }
}

impl ExactSum {
    /// An empty sum (value `0.0`).
    pub const fn new() -> Self {
        ExactSum {
            limbs: [0; LIMBS],
            pending: 0,
            nan: 0,
            pos_inf: 0,
            neg_inf: 0,
        }
    }

    /// Adds one value exactly.
    #[inline]
    pub fn add(&mut self, x: f64) {
        self.add_raw(x);
        self.pending += 1;
        if self.pending >= MAX_PENDING {
            self.normalize();
        }
    }

    /// Adds `x` to the limbs without counting it in `pending`.
    #[inline(always)]
    fn add_raw(&mut self, x: f64) {
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as u32;
        let frac = bits & ((1 << 52) - 1);
        if exp == 0x7ff {
            self.add_special(frac, (bits >> 63) != 0);
            return;
        }
        // value = mant * 2^(index - 1074)
        let (mant, index) = if exp == 0 {
            (frac, 0)
        } else {
            (frac | (1 << 52), exp - 1)
        };
        let k = (index / 32) as usize;
        let wide = u128::from(mant) << (index % 32);
        // Branch-free conditional negation: m is 0 or -1 (all ones).
        let m = -((bits >> 63) as i64);
        let parts = [
            (wide as i64) & MASK,
            ((wide >> 32) as i64) & MASK,
            (wide >> 64) as i64,
        ];
        // index <= 2045, so k + 2 <= 65 < LIMBS.
        let dst = &mut self.limbs[k..k + 3];
        for (d, p) in dst.iter_mut().zip(parts) {
            *d += (p ^ m) - m;
        }
    }

    #[cold]
    fn add_special(&mut self, frac: u64, negative: bool) {
        if frac != 0 {
            self.nan += 1;
        } else if negative {
            self.neg_inf += 1;
        } else {
            self.pos_inf += 1;
        }
    }

    /// Adds every value of `xs`.
    pub fn add_slice(&mut self, xs: &[f64]) {
        for &x in xs {
            self.add(x);
        }
    }

    /// Adds another partial sum (exact, order-independent).
    pub fn merge(&mut self, other: &ExactSum) {
        if self.pending + other.pending + 1 >= MAX_PENDING {
            self.normalize();
        }
        let mut other_pending = other.pending;
        let tmp;
        let other = if other.pending + 1 >= MAX_PENDING {
            let mut o = other.clone();
            o.normalize();
            other_pending = 0;
            tmp = o;
            &tmp
        } else {
            other
        };
        for (a, b) in self.limbs.iter_mut().zip(&other.limbs) {
            *a += *b;
        }
        self.pending += other_pending + 1;
        self.nan += other.nan;
        self.pos_inf += other.pos_inf;
        self.neg_inf += other.neg_inf;
    }

    /// Propagates carries so that limbs `0..LIMBS-1` lie in `[0, 2^32)` and the
    /// last limb carries the sign. Does not change the represented value.
    fn normalize(&mut self) {
        normalize_limbs(&mut self.limbs);
        self.pending = 0;
    }

    /// The exact sum rounded to the nearest `f64` (ties to even). Overflow
    /// gives an infinity; NaN if a NaN was added or both infinities were.
    pub fn value(&self) -> f64 {
        if self.nan > 0 || (self.pos_inf > 0 && self.neg_inf > 0) {
            return f64::NAN;
        }
        if self.pos_inf > 0 {
            return f64::INFINITY;
        }
        if self.neg_inf > 0 {
            return f64::NEG_INFINITY;
        }
        let mut l = self.limbs;
        normalize_limbs(&mut l);
        let negative = l[LIMBS - 1] < 0;
        if negative {
            for v in l.iter_mut() {
                *v = -*v;
            }
            normalize_limbs(&mut l);
        }
        let magnitude = round_magnitude(&l);
        if negative {
            -magnitude
        } else {
            magnitude
        }
    }

    /// Sums this partial sum over all ranks of `comm` (one all-reduce of
    /// integers, so exact). Every rank ends with the same sum, identical to
    /// the serial sum of all ranks' values.
    pub fn all_reduce<C: Communicator>(&mut self, comm: &C) {
        Self::all_reduce_many(std::slice::from_mut(self), comm);
    }

    /// Sums many partial sums over all ranks with a single all-reduce (e.g.
    /// the ~12 conserved quantities of a step). Every rank must pass the same
    /// number of sums.
    pub fn all_reduce_many<C: Communicator>(sums: &mut [ExactSum], comm: &C) {
        if comm.size() == 1 || sums.is_empty() {
            return;
        }
        let mut buf = Vec::with_capacity(sums.len() * WORDS);
        for s in sums.iter_mut() {
            s.normalize();
            buf.extend_from_slice(&s.limbs);
            // Counters are far below 2^63.
            buf.extend([s.nan as i64, s.pos_inf as i64, s.neg_inf as i64]);
        }
        comm.all_reduce(&mut buf, ReduceOp::Sum);
        for (s, w) in sums.iter_mut().zip(buf.chunks_exact(WORDS)) {
            s.limbs.copy_from_slice(&w[..LIMBS]);
            s.nan = w[LIMBS] as u64;
            s.pos_inf = w[LIMBS + 1] as u64;
            s.neg_inf = w[LIMBS + 2] as u64;
            // Each limb is now a sum of `size` normalised limbs (< size * 2^32).
            s.pending = comm.size() as u64;
            s.normalize();
        }
    }
}

/// Carry propagation; see [`ExactSum::normalize`].
fn normalize_limbs(l: &mut [i64; LIMBS]) {
    let mut carry = 0i64;
    for v in l[..LIMBS - 1].iter_mut() {
        let t = *v + carry;
        *v = t & MASK;
        carry = t >> 32; // floor division: t == (t & MASK) + (t >> 32) * 2^32
    }
    l[LIMBS - 1] += carry;
}

/// Rounds a normalised, non-negative accumulator to the nearest `f64`.
fn round_magnitude(l: &[i64; LIMBS]) -> f64 {
    let Some(h) = l.iter().rposition(|&v| v != 0) else {
        return 0.0;
    };
    // Bit `i` of the accumulator weighs 2^(i - 1074).
    let top = 32 * h + 63 - l[h].leading_zeros() as usize;
    // The largest finite f64 has its leading bit at 2^1023, i.e. bit 2097.
    if top > 2097 {
        return f64::INFINITY;
    }
    // Lowest kept bit: 53 significant bits, but never below 2^-1074
    // (subnormal results are exact).
    let lo = top.saturating_sub(52);
    let mut mant = bits_from(l, lo) & ((1u64 << (top - lo + 1)) - 1);
    let mut lo = lo;
    if lo > 0 {
        let r = lo - 1;
        let round = (bits_from(l, r) & 1) != 0;
        let sticky =
            l[..r / 32].iter().any(|&v| v != 0) || (l[r / 32] & ((1i64 << (r % 32)) - 1)) != 0;
        if round && (sticky || (mant & 1) != 0) {
            mant += 1;
            if mant == 1 << 53 {
                mant >>= 1;
                lo += 1;
            }
        }
    }
    // mant < 2^53 is exact in f64; scaling by a power of two is exact unless
    // it overflows, which is then the correct rounding to infinity.
    mant as f64 * pow2(lo as i32 - 1074)
}

/// 64 accumulator bits starting at bit `pos` (limbs must be normalised).
fn bits_from(l: &[i64; LIMBS], pos: usize) -> u64 {
    let k = pos / 32;
    let limb = |i: usize| -> u128 { l.get(i).map_or(0, |&v| v as u64 as u128) };
    let wide = limb(k) | (limb(k + 1) << 32) | (limb(k + 2) << 64);
    (wide >> (pos % 32)) as u64
}

/// `2^e` for `e` in `[-1074, 1023]`.
fn pow2(e: i32) -> f64 {
    debug_assert!((-1074..=1023).contains(&e));
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (e + 1074))
    }
}

impl AddAssign<f64> for ExactSum {
    fn add_assign(&mut self, x: f64) {
        self.add(x);
    }
}

impl AddAssign<&ExactSum> for ExactSum {
    fn add_assign(&mut self, other: &ExactSum) {
        self.merge(other);
    }
}

impl Extend<f64> for ExactSum {
    fn extend<I: IntoIterator<Item = f64>>(&mut self, iter: I) {
        for x in iter {
            self.add(x);
        }
    }
}

impl FromIterator<f64> for ExactSum {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        let mut s = ExactSum::new();
        s.extend(iter);
        s
    }
}

impl Sum<f64> for ExactSum {
    fn sum<I: Iterator<Item = f64>>(iter: I) -> Self {
        iter.collect()
    }
}

impl Sum<ExactSum> for ExactSum {
    fn sum<I: Iterator<Item = ExactSum>>(iter: I) -> Self {
        let mut s = ExactSum::new();
        for p in iter {
            s.merge(&p);
        }
        s
    }
}

/// The exactly rounded sum of `xs` (same bits for any permutation).
///
/// ```
/// // The exact sum of the three doubles is 2^-55; naive left-to-right
/// // addition gives 2^-54.
/// assert_eq!(sph_comm::exact_sum(&[0.1, 0.2, -0.3]), 2f64.powi(-55));
/// assert_eq!(0.1 + 0.2 - 0.3, 2f64.powi(-54));
/// ```
pub fn exact_sum(xs: &[f64]) -> f64 {
    let mut s = ExactSum::new();
    s.add_slice(xs);
    s.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Carry passes at arbitrary points, and merges of sums close to the
    /// normalisation threshold, leave the value unchanged.
    #[test]
    fn normalisation_points_do_not_matter() {
        let xs: Vec<f64> = (0..2000)
            .map(|i| {
                let x = f64::from_bits(0x9e37_79b9_7f4a_7c15u64.wrapping_mul(i as u64 + 1));
                if x.is_finite() {
                    x
                } else {
                    -(i as f64)
                }
            })
            .collect();
        let reference = exact_sum(&xs);
        for stride in [1, 3, 17, 500] {
            let mut s = ExactSum::new();
            for (i, &x) in xs.iter().enumerate() {
                s.add(x);
                if i % stride == 0 {
                    s.normalize();
                }
            }
            assert_eq!(s.value().to_bits(), reference.to_bits());
        }
        let mut a: ExactSum = xs[..1000].iter().copied().collect();
        let mut b: ExactSum = xs[1000..].iter().copied().collect();
        a.pending = MAX_PENDING - 2;
        b.pending = MAX_PENDING - 1;
        a.merge(&b);
        assert!(a.pending < MAX_PENDING);
        assert_eq!(a.value().to_bits(), reference.to_bits());
    }

    #[test]
    fn pow2_covers_the_range() {
        assert_eq!(pow2(0), 1.0);
        assert_eq!(pow2(-1074), f64::from_bits(1));
        assert_eq!(pow2(-1022), f64::MIN_POSITIVE);
        assert_eq!(pow2(1023), 2f64.powi(1023));
    }
}
