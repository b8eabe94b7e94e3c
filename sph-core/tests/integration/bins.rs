//! The bin report (`HydroConfig::bin_report`, issue 41's first measure of
//! block time steps): each particle's own step against the global one.
//! A uniform state is one bin; a blast spreads over several with its hot
//! centre at the global step; reporting changes no bit of the run; the
//! global step is at most every particle's own.

use proptest::prelude::*;
use sph_core::momentum::MomentumStats;
use sph_core::timestep::{FirstStep, TimestepParams};
use sph_core::{Hydro, HydroConfig, Particles, Scheme, StepReport, BIN_OFFSETS};
use sph_kernels::{Sinc, Tabulated};
use sph_tree::{Boundary, BoundingBox};

/// A 10^3 lattice in a periodic unit box with internal energy `u(r)`, run
/// for `steps` steps of the paper's scheme: the particles and the reports.
fn run(u: impl Fn([f64; 3]) -> f64, steps: usize, report: bool) -> (Particles, Vec<StepReport>) {
    let n = 10;
    let mut config = HydroConfig::with_scheme(Scheme::PAPER);
    config.bin_report = report;
    // The criteria's step at once: the first step is set by a particle.
    config.timestep.first_step = FirstStep::Criteria;
    config.neighbors.ng0 = 60;
    config.neighbors.ngmax = 90;
    let mut p = Particles::new(n * n * n, config.fields());
    for i in 0..p.len() {
        let c = [i % n, i / n % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64 - 0.5);
        (p.x[i], p.y[i], p.z[i]) = (c[0], c[1], c[2]);
        p.m[i] = 1.0 / p.len() as f64;
        p.h[i] = 1.3 / n as f64;
        p.u[i] = u(c);
    }
    let mut bbox = BoundingBox::cube(-0.5, 0.5, Boundary::Periodic).unwrap();
    let kernel = Tabulated::new(&Sinc::new(6.0).unwrap(), Tabulated::DEFAULT_POINTS).unwrap();
    let mut hydro = Hydro::new(kernel, config, 0.0, 1e-4).unwrap();
    hydro.prepare(&mut p);
    let reports = (0..steps)
        .map(|_| hydro.step(&mut p, &mut bbox).unwrap())
        .collect();
    (p, reports)
}

fn blast(c: [f64; 3]) -> f64 {
    1e-4 + (-(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 0.01).exp()
}

#[test]
fn a_uniform_state_is_one_bin() {
    let (p, reports) = run(|_| 1.0, 3, true);
    for r in &reports {
        let bins = r.bins.expect("reported");
        let used: Vec<usize> = (0..BIN_OFFSETS).filter(|&k| bins[k] > 0).collect();
        assert_eq!(used.len(), 1, "step {}: {bins:?}", r.step);
        assert_eq!(bins[used[0]], p.len() as u64);
    }
    // Unreported runs report nothing.
    let (_, quiet) = run(|_| 1.0, 1, false);
    assert!(quiet[0].bins.is_none());
}

#[test]
fn a_blast_spreads_over_bins_with_its_centre_at_the_global_step() {
    let (p, reports) = run(blast, 6, true);
    let last = reports.last().unwrap();
    let bins = last.bins.expect("reported");
    assert_eq!(bins.iter().sum::<u64>(), p.len() as u64);
    let used = (0..BIN_OFFSETS).filter(|&k| bins[k] > 0).count();
    assert!(used >= 3, "{bins:?}");
    // The first step is the criteria's: some particle (of the hot
    // centre) has its own step there, entry 0.
    let first = reports[0].bins.expect("reported");
    assert!(first[0] > 0, "{first:?}");
    // The cold gas (u = 1e-4 against 1 in the centre: sound speeds 100x
    // apart) could take steps many doublings longer.
    let far = (4..BIN_OFFSETS).map(|k| bins[k]).sum::<u64>();
    assert!(far > p.len() as u64 / 4, "{bins:?}");
}

#[test]
fn reporting_changes_no_bit_of_the_run() {
    let (a, _) = run(blast, 4, true);
    let (b, _) = run(blast, 4, false);
    for (name, x, y) in [
        ("x", &a.x, &b.x),
        ("vx", &a.vx, &b.vx),
        ("u", &a.u, &b.u),
        ("h", &a.h, &b.h),
        ("rho", &a.rho, &b.rho),
    ] {
        assert!(
            x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{name} differs"
        );
    }
}

proptest! {
    /// Every particle's own step is at least the global step over the
    /// same inputs (the extremes over particles), and equals it for the
    /// particle holding every extreme.
    #[test]
    fn the_global_step_is_at_most_every_particles(
        hv in proptest::collection::vec(1e-6f64..1e3, 1..20),
        div in proptest::collection::vec(0.0f64..1e4, 20),
        acc in proptest::collection::vec(0.0f64..1e4, 20),
        cool in proptest::collection::vec(0.0f64..1e6, 20),
    ) {
        let p = TimestepParams::default();
        let n = hv.len();
        let min_hv = hv.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v[..n].iter().copied().fold(0.0, f64::max);
        let stats = MomentumStats { min_h_over_vsig: min_hv, max_abs_div_v: max(&div) };
        let global = p.dt_limited(&stats, max(&acc), max(&cool), f64::INFINITY).0;
        for i in 0..n {
            prop_assert!(p.particle_dt(hv[i], div[i], acc[i], cool[i]) >= global);
        }
        prop_assert_eq!(p.particle_dt(min_hv, max(&div), max(&acc), max(&cool)), global);
    }
}
