//! 3-D FFT of a cubic grid from 1-D `rustfft` plans along each axis.

use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftDirection, FftPlanner};
use std::sync::Arc;

/// Transforms of `n^3` grids laid out as `(i n + j) n + k`, unnormalised
/// (`sum_x f(x) e^(-+2 pi i n.x / N)`).
pub(crate) struct Fft3 {
    n: usize,
    plan: Arc<dyn Fft<f64>>,
    scratch: Vec<Complex64>,
    /// One plane of lines gathered along a strided axis.
    lines: Vec<Complex64>,
}

impl Fft3 {
    /// Plans for `n`-point transforms in `direction`.
    pub(crate) fn new(n: usize, direction: FftDirection) -> Self {
        let plan = FftPlanner::new().plan_fft(n, direction);
        let scratch = vec![Complex64::default(); plan.get_inplace_scratch_len()];
        Fft3 {
            n,
            plan,
            scratch,
            lines: vec![Complex64::default(); n * n],
        }
    }

    /// Transforms `data` (`n^3` values) in place.
    pub(crate) fn process(&mut self, data: &mut [Complex64]) {
        let n = self.n;
        assert_eq!(data.len(), n * n * n, "the grid has n^3 values");
        // Along k: contiguous lines, one call for all of them.
        self.plan.process_with_scratch(data, &mut self.scratch);
        // Along j: within each slab of fixed i, gather the n lines of length n.
        for slab in data.chunks_exact_mut(n * n) {
            for j in 0..n {
                for k in 0..n {
                    self.lines[k * n + j] = slab[j * n + k];
                }
            }
            self.plan
                .process_with_scratch(&mut self.lines, &mut self.scratch);
            for j in 0..n {
                for k in 0..n {
                    slab[j * n + k] = self.lines[k * n + j];
                }
            }
        }
        // Along i: for each j, the plane of (i, k) lines.
        for j in 0..n {
            for i in 0..n {
                for k in 0..n {
                    self.lines[k * n + i] = data[(i * n + j) * n + k];
                }
            }
            self.plan
                .process_with_scratch(&mut self.lines, &mut self.scratch);
            for i in 0..n {
                for k in 0..n {
                    data[(i * n + j) * n + k] = self.lines[k * n + i];
                }
            }
        }
    }
}

impl std::fmt::Debug for Fft3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fft3")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}
