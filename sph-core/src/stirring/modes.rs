//! The driven Fourier modes: SPH-EXA's list of wave vectors, with its order
//! and its repeated entries, and their amplitudes.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The shape of the driving spectrum over the band `1 <= |n| <= 3`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Spectrum {
    /// SPH-EXA's default (`stSpectForm` 1): a parabola in `k` peaking at
    /// the middle of the band and vanishing at its edges.
    #[default]
    Parabolic,
}

/// Lowest and highest `|n|` of the band, widened by 1e-15 as in the C++
/// code so that `|n| = 1` and `|n| = 3` are inside (with amplitudes of
/// about 2e-7 rather than 0).
const N_MIN: f64 = 1.0 - 1e-15;
const N_MAX: f64 = 3.0 + 1e-15;

/// The mode entries, `k = 2 pi n / L` with integer `n`.
///
/// Every triple `nx, ny, nz >= 0` with `N_MIN <= |n| <= N_MAX`, scanned with
/// `nx` outermost and `nz` innermost, adds four entries `(nx, ny, nz)`,
/// `(nx, -ny, nz)`, `(nx, ny, -nz)`, `(nx, -ny, -nz)`. As `-0 = 0`, triples
/// on coordinate planes list the same vector two or four times: 112 entries,
/// 75 distinct vectors. The repeats are kept (each has its own OU phases),
/// so that a run draws the same numbers for the same entries as the C++ one.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeSet {
    /// Integer wave numbers per entry: `nx` in `[0, 3]`, `ny` and `nz` in
    /// `[-3, 3]` (the field code indexes its tables by them).
    pub n: Vec<[i8; 3]>,
    /// Amplitude per entry (the spectrum at `|n|`).
    pub amp: Vec<f64>,
    /// Wave vectors `2 pi n / L` per entry.
    pub k: Vec<[f64; 3]>,
}

impl ModeSet {
    /// The entries for a periodic cube of side `length`.
    pub fn new(length: f64, spectrum: Spectrum) -> Self {
        let top = N_MAX.floor() as i8;
        let mut n = Vec::new();
        for nx in 0..=top {
            for ny in 0..=top {
                for nz in 0..=top {
                    let norm = norm([nx, ny, nz]);
                    if (N_MIN..=N_MAX).contains(&norm) {
                        for (sy, sz) in [(1, 1), (-1, 1), (1, -1), (-1, -1)] {
                            n.push([nx, sy * ny, sz * nz]);
                        }
                    }
                }
            }
        }
        let amp = n.iter().map(|&v| amplitude(spectrum, norm(v))).collect();
        let k = n
            .iter()
            .map(|v| v.map(|c| 2.0 * PI * f64::from(c) / length))
            .collect();
        Self { n, amp, k }
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.n.len()
    }

    /// Whether there are no entries.
    pub fn is_empty(&self) -> bool {
        self.n.is_empty()
    }
}

fn norm(n: [i8; 3]) -> f64 {
    n.map(f64::from).iter().map(|c| c * c).sum::<f64>().sqrt()
}

/// Amplitude at `|n|` (the ratios of `k` do not depend on `L`).
fn amplitude(spectrum: Spectrum, n: f64) -> f64 {
    match spectrum {
        Spectrum::Parabolic => {
            let centre = 0.5 * (N_MIN + N_MAX);
            let width = N_MAX - N_MIN;
            let d = n - centre;
            let a = (1.0 - 4.0 * d * d / (width * width)).abs();
            2.0 * a.sqrt() * centre / n
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> ModeSet {
        ModeSet::new(1.0, Spectrum::Parabolic)
    }

    #[test]
    fn count_and_distinct_vectors() {
        let m = unit();
        assert_eq!(m.len(), 112);
        let mut d = m.n.clone();
        d.sort();
        d.dedup();
        assert_eq!(d.len(), 75);
    }

    #[test]
    fn order_of_the_first_entries() {
        let m = unit();
        let first: [[i8; 3]; 12] = [
            [0, 0, 1],
            [0, 0, 1],
            [0, 0, -1],
            [0, 0, -1],
            [0, 0, 2],
            [0, 0, 2],
            [0, 0, -2],
            [0, 0, -2],
            [0, 0, 3],
            [0, 0, 3],
            [0, 0, -3],
            [0, 0, -3],
        ];
        assert_eq!(m.n[..12], first);
        assert_eq!(
            m.n[12..20],
            [
                [0, 1, 0],
                [0, -1, 0],
                [0, 1, 0],
                [0, -1, 0],
                [0, 1, 1],
                [0, -1, 1],
                [0, 1, -1],
                [0, -1, -1]
            ]
        );
        assert_eq!(m.n[111], [3, 0, 0]);
    }

    #[test]
    fn amplitudes_closed_forms() {
        let m = unit();
        let r2 = 2f64.sqrt();
        let at_sqrt2 = 2.0 * (1.0 - (r2 - 2.0).powi(2)).sqrt() * 2.0 / r2;
        let mut forcing = 0;
        let mut sum2 = 0.0;
        for (n, &a) in m.n.iter().zip(&m.amp) {
            let n2: i32 = n.iter().map(|&c| i32::from(c) * i32::from(c)).sum();
            match n2 {
                4 => assert!((a - 2.0).abs() < 1e-12, "{n:?}: {a}"),
                2 => assert!((a - at_sqrt2).abs() < 1e-12, "{n:?}: {a}"),
                1 | 9 => assert!(a < 1e-6, "band edge {n:?}: {a}"),
                _ => {}
            }
            if a > 1e-6 {
                forcing += 1;
            }
            sum2 += a * a;
        }
        assert_eq!(forcing, 76);
        assert!((sum2 - 236.4).abs() < 0.05, "sum amp^2 = {sum2}");
    }

    #[test]
    fn wave_vectors_scale_with_the_box() {
        let m = ModeSet::new(2.0, Spectrum::Parabolic);
        assert_eq!(m.amp, unit().amp);
        for (n, k) in m.n.iter().zip(&m.k) {
            for c in 0..3 {
                assert!((k[c] - PI * f64::from(n[c])).abs() < 1e-15);
            }
        }
    }
}
