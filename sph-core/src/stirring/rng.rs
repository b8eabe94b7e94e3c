//! The random numbers of the driving, as the C++ code draws them:
//! [`Mt19937`] (the standard 32-bit Mersenne Twister of `std::mt19937`) and
//! [`Polar`], the normal deviates of libstdc++'s
//! `std::normal_distribution<double>` on that engine. With the same seed
//! the OU phases are the C++ run's, number for number.

use crate::CoreError;

const N: usize = 624;
const M: usize = 397;
const MATRIX_A: u32 = 0x9908_b0df;
const UPPER: u32 = 0x8000_0000;
const LOWER: u32 = 0x7fff_ffff;

/// Length of [`Mt19937::state`]: the 624 words, then the index of the next
/// word to temper.
pub const STATE_LEN: usize = N + 1;

/// The 32-bit Mersenne Twister MT19937 (Matsumoto and Nishimura 1998),
/// seeded as `std::mt19937` is.
///
/// ```
/// use sph_core::stirring::rng::Mt19937;
/// let mut g = Mt19937::new(5489);
/// let last = (0..10_000).map(|_| g.next_u32()).last();
/// assert_eq!(last, Some(4_123_659_995)); // the C++ standard's check
/// ```
#[derive(Clone, PartialEq, Eq)]
pub struct Mt19937 {
    words: [u32; N],
    index: usize,
}

impl std::fmt::Debug for Mt19937 {
    // 624 words say nothing to a reader; the index and the first word do.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mt19937")
            .field("index", &self.index)
            .field("words[0]", &self.words[0])
            .finish_non_exhaustive()
    }
}

impl Mt19937 {
    /// The generator seeded with `seed` (`std::mt19937(seed)`).
    pub fn new(seed: u32) -> Self {
        let mut words = [0u32; N];
        words[0] = seed;
        for i in 1..N {
            let prev = words[i - 1];
            words[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        // The first call regenerates the whole block, as the C++ engine does.
        Self { words, index: N }
    }

    /// The next 32-bit output.
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= N {
            self.twist();
        }
        let mut y = self.words[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    fn twist(&mut self) {
        for i in 0..N {
            let y = (self.words[i] & UPPER) | (self.words[(i + 1) % N] & LOWER);
            let mag = if y & 1 == 1 { MATRIX_A } else { 0 };
            self.words[i] = self.words[(i + M) % N] ^ (y >> 1) ^ mag;
        }
        self.index = 0;
    }

    /// A uniform double in `[0, 1)` as libstdc++'s
    /// `std::generate_canonical<double, 53>` makes it from two outputs `a`
    /// then `b`: `(a + b 2^32) / 2^64`, the sum rounded to a double, and a
    /// result that rounds up to 1 replaced by the largest double below 1.
    pub fn next_canonical(&mut self) -> f64 {
        const TWO_32: f64 = 4_294_967_296.0;
        let a = f64::from(self.next_u32());
        let b = f64::from(self.next_u32());
        let r = (a + b * TWO_32) / (TWO_32 * TWO_32);
        if r >= 1.0 {
            1.0 - f64::EPSILON / 2.0
        } else {
            r
        }
    }

    /// The state as [`STATE_LEN`] exact integers (the 624 words, then the
    /// index), for checkpoints: `f64` holds them without rounding.
    pub fn state(&self) -> Vec<f64> {
        let mut s: Vec<f64> = self.words.iter().map(|&w| f64::from(w)).collect();
        s.push(self.index as f64);
        s
    }

    /// The generator from a [`state`](Self::state); refuses a wrong length,
    /// words that are not integers in `[0, 2^32)` and an index above 624.
    pub fn from_state(state: &[f64]) -> Result<Self, CoreError> {
        if state.len() != STATE_LEN {
            return Err(CoreError::Invalid(format!(
                "stirring: random-number state has {} values, expected {STATE_LEN} (624 words and an index)",
                state.len()
            )));
        }
        let mut words = [0u32; N];
        for (i, (&v, w)) in state.iter().zip(words.iter_mut()).enumerate() {
            if !(v.fract() == 0.0 && (0.0..4_294_967_296.0).contains(&v)) {
                return Err(CoreError::Invalid(format!(
                    "stirring: random-number state word {i} is {v}, expected an integer in [0, 2^32)"
                )));
            }
            *w = v as u32;
        }
        let index = state[N];
        if !(index.fract() == 0.0 && (0.0..=N as f64).contains(&index)) {
            return Err(CoreError::Invalid(format!(
                "stirring: random-number state index is {index}, expected an integer in [0, 624]"
            )));
        }
        if words.iter().all(|&w| w == 0) {
            return Err(CoreError::Invalid(
                "stirring: random-number state words are all zero (not a Mersenne Twister state)"
                    .into(),
            ));
        }
        Ok(Self {
            words,
            index: index as usize,
        })
    }
}

/// Standard normal deviates by Marsaglia's polar method, as libstdc++'s
/// `std::normal_distribution<double>` draws them: a pair per accepted point
/// of the unit disc, the `y` value returned first and the `x` value kept for
/// the next call.
///
/// The C++ driver makes a new distribution for every step, so a kept value
/// never outlives a step: make a new `Polar` for each step too.
#[derive(Debug, Clone, Default)]
pub struct Polar {
    kept: Option<f64>,
}

impl Polar {
    /// A fresh distribution with no kept value.
    pub fn new() -> Self {
        Self::default()
    }

    /// The next standard normal deviate.
    pub fn sample(&mut self, rng: &mut Mt19937) -> f64 {
        if let Some(v) = self.kept.take() {
            return v;
        }
        loop {
            let x = 2.0 * rng.next_canonical() - 1.0;
            let y = 2.0 * rng.next_canonical() - 1.0;
            let r2 = x * x + y * y;
            if r2 <= 1.0 && r2 != 0.0 {
                let mult = (-2.0 * r2.ln() / r2).sqrt();
                self.kept = Some(x * mult);
                return y * mult;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mt19937_ten_thousandth_output() {
        let mut g = Mt19937::new(5489);
        for _ in 0..9_999 {
            g.next_u32();
        }
        assert_eq!(g.next_u32(), 4_123_659_995);
    }

    #[test]
    fn mt19937_first_outputs_of_seed_5489() {
        // The reference implementation's first outputs (mt19937ar.c, same seeding).
        let mut g = Mt19937::new(5489);
        let first: Vec<u32> = (0..3).map(|_| g.next_u32()).collect();
        assert_eq!(first, [3_499_211_612, 581_869_302, 3_890_346_734]);
    }

    #[test]
    fn state_round_trip_continues_identically() {
        let mut g = Mt19937::new(251_299);
        for _ in 0..1_000 {
            g.next_u32();
        }
        let s = g.state();
        assert_eq!(s.len(), STATE_LEN);
        let mut h = Mt19937::from_state(&s).unwrap();
        assert_eq!(h, g);
        for _ in 0..2_000 {
            assert_eq!(h.next_u32(), g.next_u32());
        }
        // At the block edge too (index 624: the next call twists).
        let mut fresh = Mt19937::new(7);
        let mut again = Mt19937::from_state(&fresh.state()).unwrap();
        assert_eq!(again.next_u32(), fresh.next_u32());
    }

    #[test]
    fn state_refusals_name_the_problem() {
        let s = Mt19937::new(1).state();
        let msg = |r: Result<Mt19937, CoreError>| r.unwrap_err().to_string();
        assert!(msg(Mt19937::from_state(&s[..624])).contains("624 values"));
        let mut bad = s.clone();
        bad[3] = 0.5;
        assert!(msg(Mt19937::from_state(&bad)).contains("word 3 is 0.5"));
        bad = s.clone();
        bad[624] = 625.0;
        assert!(msg(Mt19937::from_state(&bad)).contains("index is 625"));
        bad = vec![0.0; STATE_LEN];
        assert!(msg(Mt19937::from_state(&bad)).contains("all zero"));
    }

    #[test]
    fn canonical_is_the_two_word_formula() {
        let mut g = Mt19937::new(42);
        let mut h = g.clone();
        let u = g.next_canonical();
        let (a, b) = (h.next_u32() as f64, h.next_u32() as f64);
        assert_eq!(u, (a + b * 2f64.powi(32)) * 2f64.powi(-64));
        assert!((0.0..1.0).contains(&u));
    }

    #[test]
    fn polar_pairs_keep_the_second_value() {
        let mut g = Mt19937::new(3);
        let mut h = g.clone();
        let mut p = Polar::new();
        let (z0, z1) = (p.sample(&mut g), p.sample(&mut g));
        // The pair by hand: the first accepted point, y first.
        let (x, y, r2) = loop {
            let x = 2.0 * h.next_canonical() - 1.0;
            let y = 2.0 * h.next_canonical() - 1.0;
            let r2 = x * x + y * y;
            if r2 <= 1.0 && r2 != 0.0 {
                break (x, y, r2);
            }
        };
        let mult = (-2.0 * r2.ln() / r2).sqrt();
        assert_eq!((z0, z1), (y * mult, x * mult));
        // The kept value used no words.
        assert_eq!(g, h);
    }

    #[test]
    fn polar_mean_and_variance() {
        let mut g = Mt19937::new(251_299);
        let mut p = Polar::new();
        let n = 1_000_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let z = p.sample(&mut g);
            s1 += z;
            s2 += z * z;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        eprintln!("polar normals: mean {mean:.2e}, variance {var:.5}");
        // Standard errors 1e-3 (mean) and 1.4e-3 (variance): 5e-3 is over 3.5 of them.
        assert!(mean.abs() < 5e-3, "mean {mean}");
        assert!((var - 1.0).abs() < 5e-3, "variance {var}");
    }
}
