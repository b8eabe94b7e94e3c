//! The timing figures of a run, summed over its steps: seconds per stage
//! (one per name of [`STAGES`]), decomposition figures and the time-step
//! limits, as means over steps 2..N (step 1 holds set-up costs). They feed
//! `timings.csv` ([`super::timings`]) and the summary.

use sph_core::{StepReport, BIN_OFFSETS, STAGES};
use std::collections::BTreeMap;

/// Decomposition figures of a run (means over steps 2..N).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct DomainSummary {
    /// Fewest particles on a rank (last step).
    pub owned_min: usize,
    /// Most particles on a rank (last step).
    pub owned_max: usize,
    /// Mean over steps of total halos / total owned.
    pub halo_ratio_mean: f64,
    /// Mean over steps of the largest halos / owned of a rank.
    pub halo_ratio_max: f64,
    /// Mean bytes sent per step, all ranks together.
    pub bytes_sent_per_step: f64,
    /// Mean over steps of the longest per-rank time in domain communication.
    pub comm_seconds_per_step: f64,
    /// Mean over steps of the longest per-rank time in `sync`.
    pub sync_seconds_per_step: f64,
}

/// The time bins a block-step run would give the particles
/// (`sphexa run --report-bins`, [`sph_core::HydroConfig::bin_report`]), over
/// all steps: an estimate before block steps exist, without their limiter
/// or longest step (so a lower bound of their updates).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct BinSummary {
    /// Entry `k`: particle-steps whose own step was at least `2^k` (below
    /// the last entry less than `2^(k+1)`) times the global step.
    pub particle_steps_by_offset: Vec<u64>,
    /// Particle updates of this run (particles times steps).
    pub global_updates: u64,
    /// The updates if each particle advanced with its own step rounded
    /// down to a power of two of the global one: the sum over steps and
    /// particles of `2^-k`.
    pub block_updates_estimate: f64,
    /// `block_updates_estimate / global_updates`.
    pub ratio: f64,
}

/// Sums of the per-step figures over steps 2..N, and the last step's.
#[derive(Debug, Clone)]
pub struct StageTotals {
    total: usize,
    stage_sum: Vec<f64>,
    domain: DomainSummary,
    timed_steps: u64,
    /// Particle updates over steps 2..N.
    timed_updates: u64,
    last_total: Option<f64>,
    limits: BTreeMap<&'static str, u64>,
    bins: Option<BinSummary>,
}

impl StageTotals {
    /// Nothing recorded yet, for a run with `total` particles (the
    /// denominator of the halo ratio).
    pub fn new(total: usize) -> Self {
        Self {
            total,
            stage_sum: vec![0.0; STAGES.len()],
            domain: DomainSummary::default(),
            timed_steps: 0,
            timed_updates: 0,
            last_total: None,
            limits: BTreeMap::new(),
            bins: None,
        }
    }

    /// Halos over owned particles, all ranks together, in step `r`.
    pub(super) fn halo_ratio(&self, r: &StepReport) -> f64 {
        r.domain.halos_total as f64 / self.total.max(1) as f64
    }

    /// Adds step `r` (to the means from step 2 on).
    pub fn record(&mut self, r: &StepReport) {
        let d = r.domain;
        if r.step >= 2 {
            for (s, t) in self.stage_sum.iter_mut().zip(r.times.0.iter()) {
                *s += t;
            }
            let halo_ratio = self.halo_ratio(r);
            let dom = &mut self.domain;
            dom.halo_ratio_mean += halo_ratio;
            dom.halo_ratio_max += d.halo_ratio_max;
            dom.bytes_sent_per_step += d.bytes_sent as f64;
            dom.comm_seconds_per_step += d.comm_seconds_max;
            dom.sync_seconds_per_step += d.sync_seconds_max;
            self.timed_steps += 1;
            self.timed_updates += r.updates;
        }
        (self.domain.owned_min, self.domain.owned_max) = (d.owned_min, d.owned_max);
        self.last_total = Some(r.times.total());
        *self.limits.entry(r.dt_limit.name()).or_default() += 1;
        if let Some(counts) = r.bins {
            let b = self.bins.get_or_insert_with(|| BinSummary {
                particle_steps_by_offset: vec![0; BIN_OFFSETS],
                ..BinSummary::default()
            });
            for (k, &c) in counts.iter().enumerate() {
                b.particle_steps_by_offset[k] += c;
                b.global_updates += c;
                b.block_updates_estimate += c as f64 * 0.5f64.powi(k as i32);
            }
            b.ratio = b.block_updates_estimate / b.global_updates.max(1) as f64;
        }
    }

    /// The bins the particles would take, where the run measured them.
    pub fn bins(&self) -> Option<BinSummary> {
        self.bins.clone()
    }

    /// How many steps each time-step criterion set.
    pub fn dt_limits(&self) -> BTreeMap<String, u64> {
        self.limits
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect()
    }

    /// Mean particle updates per step over steps 2..N (all particles in
    /// a global run; the active ones per sub-step with block steps).
    pub fn mean_updates(&self) -> f64 {
        self.timed_updates as f64 / self.steps_div()
    }

    fn steps_div(&self) -> f64 {
        self.timed_steps.max(1) as f64
    }

    /// Mean seconds per step over steps 2..N (the only step's time if the
    /// run had one, NaN if none).
    pub fn mean_step_s(&self) -> f64 {
        if self.timed_steps > 0 {
            self.stage_sum.iter().sum::<f64>() / self.timed_steps as f64
        } else {
            self.last_total.unwrap_or(f64::NAN)
        }
    }

    /// Mean seconds per stage over steps 2..N, in the order of [`STAGES`].
    pub fn stage_means(&self) -> Vec<f64> {
        let k = self.steps_div();
        self.stage_sum.iter().map(|s| s / k).collect()
    }

    /// Mean seconds per stage over steps 2..N, by stage name.
    pub fn stage_seconds(&self) -> BTreeMap<String, f64> {
        STAGES
            .iter()
            .map(|name| name.to_string())
            .zip(self.stage_means())
            .collect()
    }

    /// Decomposition figures: means over steps 2..N, owned counts of the
    /// last step.
    pub fn domain(&self) -> DomainSummary {
        let k = self.steps_div();
        let d = self.domain;
        DomainSummary {
            halo_ratio_mean: d.halo_ratio_mean / k,
            halo_ratio_max: d.halo_ratio_max / k,
            bytes_sent_per_step: d.bytes_sent_per_step / k,
            comm_seconds_per_step: d.comm_seconds_per_step / k,
            sync_seconds_per_step: d.sync_seconds_per_step / k,
            ..d
        }
    }
}
