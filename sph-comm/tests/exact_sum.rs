//! Property tests of `ExactSum`: order independence, exact rounding against
//! independent references, merges, IEEE special values.

use proptest::prelude::*;
use sph_comm::{exact_sum, ExactSum, SerialComm};

/// Correctly rounded sum by Shewchuk's exact partials with the round-half-even
/// correction (the algorithm of Python's `math.fsum`). Valid while no partial
/// overflows, i.e. for |x| well below `f64::MAX`.
fn fsum(xs: &[f64]) -> f64 {
    let mut partials: Vec<f64> = Vec::new();
    for &x0 in xs {
        let mut x = x0;
        let mut i = 0;
        for j in 0..partials.len() {
            let mut y = partials[j];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            let lo = y - (hi - x);
            if lo != 0.0 {
                partials[i] = lo;
                i += 1;
            }
            x = hi;
        }
        partials.truncate(i);
        partials.push(x);
    }
    let mut n = partials.len();
    if n == 0 {
        return 0.0;
    }
    n -= 1;
    let mut hi = partials[n];
    let mut lo = 0.0;
    while n > 0 {
        let x = hi;
        n -= 1;
        let y = partials[n];
        hi = x + y;
        let yr = hi - x;
        lo = y - yr;
        if lo != 0.0 {
            break;
        }
    }
    if n > 0 && ((lo < 0.0 && partials[n - 1] < 0.0) || (lo > 0.0 && partials[n - 1] > 0.0)) {
        let y = lo * 2.0;
        let x = hi + y;
        let yr = x - hi;
        if y == yr {
            hi = x;
        }
    }
    hi
}

/// Any finite double, uniformly over bit patterns (all exponents, subnormals).
fn any_finite() -> impl Strategy<Value = f64> {
    any::<u64>()
        .prop_map(f64::from_bits)
        .prop_filter("finite", |x| x.is_finite())
}

/// Finite doubles with |x| < 2^990, so that fsum's partials cannot overflow.
fn moderate() -> impl Strategy<Value = f64> {
    prop_oneof![
        any_finite().prop_filter("moderate", |x| x.abs() < 2f64.powi(990)),
        (-1e6f64..1e6),
        (-1.0f64..1.0).prop_map(|x| x * 1e-300),
    ]
}

/// Values with large cancellations: a set together with most of its negations.
fn cancelling() -> impl Strategy<Value = Vec<f64>> {
    (
        prop::collection::vec(moderate(), 0..40),
        prop::collection::vec(any::<bool>(), 40),
        prop::collection::vec(moderate(), 0..4),
    )
        .prop_map(|(xs, keep, extra)| {
            let mut v = xs.clone();
            v.extend(xs.iter().zip(keep).filter(|(_, k)| *k).map(|(x, _)| -x));
            v.extend(extra);
            v
        })
}

/// A permutation of `xs` given by sort keys, then a split into chunks.
fn permuted_chunks(xs: &[f64], keys: &[u32], cuts: &[usize]) -> Vec<Vec<f64>> {
    let mut idx: Vec<usize> = (0..xs.len()).collect();
    idx.sort_by_key(|&i| (keys[i % keys.len()], i));
    let perm: Vec<f64> = idx.iter().map(|&i| xs[i]).collect();
    let mut bounds: Vec<usize> = cuts
        .iter()
        .map(|c| {
            if perm.is_empty() {
                0
            } else {
                c % (perm.len() + 1)
            }
        })
        .collect();
    bounds.push(0);
    bounds.push(perm.len());
    bounds.sort_unstable();
    bounds
        .windows(2)
        .map(|w| perm[w[0]..w[1]].to_vec())
        .collect()
}

fn bits(x: f64) -> u64 {
    x.to_bits()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn any_permutation_and_split_gives_identical_bits(
        xs in prop::collection::vec(any_finite(), 0..80),
        keys in prop::collection::vec(any::<u32>(), 1..80),
        cuts in prop::collection::vec(any::<usize>(), 0..6),
        merge_keys in prop::collection::vec(any::<u32>(), 8),
    ) {
        let reference = exact_sum(&xs);
        let chunks = permuted_chunks(&xs, &keys, &cuts);
        let mut parts: Vec<ExactSum> = chunks.iter().map(|c| c.iter().copied().collect()).collect();
        // Merge the partial sums in a scrambled order.
        let mut order: Vec<usize> = (0..parts.len()).collect();
        order.sort_by_key(|&i| (merge_keys[i % merge_keys.len()], i));
        let mut total = ExactSum::new();
        for i in order {
            total.merge(&parts[i]);
        }
        prop_assert_eq!(bits(total.value()), bits(reference));
        // A tree of merges (pairwise, like a rayon reduction).
        while parts.len() > 1 {
            let b = parts.pop().unwrap();
            let a = parts.pop().unwrap();
            let mut ab = a;
            ab += &b;
            parts.insert(0, ab);
        }
        let tree = parts.pop().unwrap_or_default();
        prop_assert_eq!(bits(tree.value()), bits(reference));
        // Reversed input.
        let rev: ExactSum = xs.iter().rev().copied().sum();
        prop_assert_eq!(bits(rev.value()), bits(reference));
    }

    #[test]
    fn equals_correctly_rounded_fsum(xs in prop::collection::vec(moderate(), 0..100)) {
        let got = exact_sum(&xs);
        let want = fsum(&xs);
        prop_assert!(got == want, "{:?}: {} vs fsum {}", xs, got, want);
        if want != 0.0 {
            prop_assert_eq!(bits(got), bits(want));
        }
    }

    #[test]
    fn cancellation_equals_fsum(xs in cancelling(), keys in prop::collection::vec(any::<u32>(), 1..80)) {
        let chunks = permuted_chunks(&xs, &keys, &[]);
        let got = exact_sum(&chunks[0]);
        let want = fsum(&xs);
        prop_assert!(got == want, "{} vs fsum {}", got, want);
    }

    /// Independent integer reference: x = k 2^e with |k| < 2^40 and
    /// e in [-60, 20], so 2^60 x is an integer and the sum of 64 of them fits
    /// an i128; `i128 as f64` rounds to nearest even.
    #[test]
    fn equals_i128_fixed_point_reference(
        terms in prop::collection::vec((-(1i64 << 40)..(1i64 << 40), -60i32..=20), 0..64)
    ) {
        let xs: Vec<f64> = terms.iter().map(|&(k, e)| k as f64 * 2f64.powi(e)).collect();
        let fixed: i128 = terms.iter().map(|&(k, e)| (k as i128) << (e + 60)).sum();
        let want = fixed as f64 * 2f64.powi(-60);
        let got = exact_sum(&xs);
        prop_assert!(got == want, "{} vs {}", got, want);
    }

    /// Sparse significands (few bits set over a 70-bit span) make the
    /// rounding ties of round-half-even frequent.
    #[test]
    fn ties_round_to_even(
        terms in prop::collection::vec((-8i64..8, 0u32..70), 1..8),
        scale in -1000i32..900,
    ) {
        let fixed: i128 = terms.iter().map(|&(k, e)| (k as i128) << e).sum();
        let s = 2f64.powi(scale);
        let xs: Vec<f64> = terms.iter().map(|&(k, e)| k as f64 * 2f64.powi(e as i32) * s).collect();
        let want = fixed as f64 * s;
        prop_assume!(want.is_finite() && (want == 0.0 || want.abs() >= f64::MIN_POSITIVE));
        prop_assert!(exact_sum(&xs) == want);
    }

    #[test]
    fn two_term_ties(k in 0u64..(1 << 52), sign in any::<bool>(), e in -1000i32..1000) {
        let a = f64::from_bits(((e + 1023) as u64) << 52 | k);
        let half_ulp = if sign { 2f64.powi(e - 53) } else { -2f64.powi(e - 54) };
        prop_assert_eq!(bits(exact_sum(&[a, half_ulp])), bits(a + half_ulp));
        prop_assert_eq!(bits(exact_sum(&[half_ulp, a, 0.0])), bits(a + half_ulp));
    }

    /// A single IEEE addition is correctly rounded, so the exact sum of two
    /// values must be `a + b`; and `a + b - fl(a + b)` is exactly the TwoSum
    /// error, over the whole finite range.
    #[test]
    fn two_terms_match_ieee_and_two_sum(a in any_finite(), b in any_finite()) {
        let s = a + b;
        prop_assume!(s.is_finite());
        let got = exact_sum(&[a, b]);
        prop_assert!(got == s);
        if s != 0.0 {
            prop_assert_eq!(bits(got), bits(s));
        }
        let bb = s - a;
        let err = (a - (s - bb)) + (b - bb);
        prop_assert!(exact_sum(&[a, b, -s]) == err);
        prop_assert!(exact_sum(&[-s, b, a]) == err);
    }

    #[test]
    fn negation_is_symmetric(xs in prop::collection::vec(any_finite(), 0..50)) {
        let neg: Vec<f64> = xs.iter().map(|x| -x).collect();
        prop_assert!(exact_sum(&neg) == -exact_sum(&xs));
        let mut both = xs.clone();
        both.extend(&neg);
        prop_assert_eq!(bits(exact_sum(&both)), 0);
    }

    #[test]
    fn many_sums_reduce_like_single_sums(xs in prop::collection::vec(any_finite(), 0..40)) {
        let mut sums = vec![ExactSum::new(); 3];
        for (i, &x) in xs.iter().enumerate() {
            sums[i % 3].add(x);
        }
        let before: Vec<u64> = sums.iter().map(|s| bits(s.value())).collect();
        ExactSum::all_reduce_many(&mut sums, &SerialComm);
        let after: Vec<u64> = sums.iter().map(|s| bits(s.value())).collect();
        prop_assert_eq!(before, after);
    }
}

#[test]
fn catastrophic_cancellation() {
    assert_eq!(exact_sum(&[1e308, 1.0, -1e308]), 1.0);
    assert_eq!(exact_sum(&[1e308, 1e-300, -1e308]), 1e-300);
    assert_eq!(exact_sum(&[f64::MAX, f64::MAX, -f64::MAX]), f64::MAX);
    assert_eq!(exact_sum(&[0.1, 0.2, -0.3]), 2f64.powi(-55));
}

#[test]
fn ties_to_even() {
    let eps = f64::EPSILON;
    assert_eq!(exact_sum(&[1.0, eps / 2.0]), 1.0);
    assert_eq!(exact_sum(&[1.0 + eps, eps / 2.0]), 1.0 + 2.0 * eps);
    assert_eq!(exact_sum(&[1.0, eps / 2.0, 1e-300]), 1.0 + eps);
    assert_eq!(exact_sum(&[1.0, eps / 2.0, -1e-300]), 1.0);
    assert_eq!(exact_sum(&[-1.0, -eps / 2.0]), -1.0);
}

#[test]
fn overflow_and_rounding_at_the_top() {
    assert_eq!(exact_sum(&[f64::MAX, f64::MAX]), f64::INFINITY);
    assert_eq!(exact_sum(&[-f64::MAX, -f64::MAX]), f64::NEG_INFINITY);
    // Half an ulp of MAX rounds to even, i.e. up, to infinity (as IEEE does).
    assert_eq!(
        exact_sum(&[f64::MAX, 2f64.powi(970)]),
        f64::MAX + 2f64.powi(970)
    );
    assert_eq!(exact_sum(&[f64::MAX, 2f64.powi(970)]), f64::INFINITY);
    assert_eq!(exact_sum(&[f64::MAX, 2f64.powi(969)]), f64::MAX);
    // Overflow in an intermediate does not matter: only the exact sum counts.
    assert_eq!(
        exact_sum(&[f64::MAX, f64::MAX, f64::MAX, -f64::MAX, -f64::MAX]),
        f64::MAX
    );
}

#[test]
fn subnormals_are_exact() {
    let tiny = f64::from_bits(1);
    assert_eq!(exact_sum(&[tiny; 3]), f64::from_bits(3));
    assert_eq!(exact_sum(&[tiny, -tiny]), 0.0);
    let big_sub = f64::from_bits((1 << 52) - 1);
    assert_eq!(exact_sum(&[big_sub, tiny]), f64::MIN_POSITIVE);
    assert_eq!(exact_sum(&[f64::MIN_POSITIVE, -tiny]), big_sub);
}

#[test]
fn special_values() {
    assert!(exact_sum(&[f64::INFINITY, f64::NEG_INFINITY]).is_nan());
    assert!(exact_sum(&[1.0, f64::NAN]).is_nan());
    assert_eq!(exact_sum(&[f64::INFINITY, -f64::MAX, 1.0]), f64::INFINITY);
    assert_eq!(exact_sum(&[f64::NEG_INFINITY, 1.0]), f64::NEG_INFINITY);
    assert_eq!(exact_sum(&[]).to_bits(), 0);
    assert_eq!(exact_sum(&[-0.0, 0.0, -0.0]).to_bits(), 0);
}

#[test]
fn a_million_tenths() {
    // 0.1 = m 2^-56 exactly; the exact sum is 10^6 m 2^-56.
    let m = (0.1f64 * 2f64.powi(56)) as i128;
    assert_eq!(m as f64 * 2f64.powi(-56), 0.1);
    let want = (m * 1_000_000) as f64 * 2f64.powi(-56);
    let got: ExactSum = std::iter::repeat_n(0.1, 1_000_000).collect();
    assert_eq!(got.value(), want);
}

#[test]
fn rayon_sum_is_independent_of_thread_count() {
    use rayon::prelude::*;
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let xs: Vec<f64> = (0..100_000)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mag = (state >> 11) as f64 / (1u64 << 53) as f64;
            let e = (state % 200) as i32 - 100;
            if state & 1 == 0 {
                mag * 2f64.powi(e)
            } else {
                -mag * 2f64.powi(e)
            }
        })
        .collect();
    let serial = exact_sum(&xs);
    for threads in [1, 2, 3, 7] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let par: ExactSum = pool.install(|| xs.par_iter().copied().sum());
        assert_eq!(par.value().to_bits(), serial.to_bits(), "{threads} threads");
    }
    assert_eq!(serial, fsum(&xs));
}
