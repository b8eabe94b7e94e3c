//! The stages of a step, in pipeline order.

use super::report::{Stage, StageClock, BIN_OFFSETS};
use super::Hydro;
use crate::av_switch::{
    balsara, iad_and_velocity_divergence, update_alpha_over, velocity_divergence, Elapsed,
    FlowState,
};
use crate::conduction::{Conductivity, ImpulseWeights};
use crate::density::{density, pressure_energy_density, ve_density, xmass, Positions, VeOut};
use crate::iad::iad_volumes;
use crate::integrate::HUpdate;
use crate::momentum::{
    momentum_energy_with, Alpha, ArtificialStress, AvCleaning, Criteria, HydroState,
    MomentumScheme, MomentumStats, Rates, VolumeWeights,
};
use crate::neighbors::find_neighbors_of;
use crate::scheme::{Viscosity, Volume};
use crate::{CoreError, Particles, TimestepParams};
use rayon::prelude::*;
use sph_comm::{Communicator, ReduceOp};
use sph_gravity::{Decomposition, GravityStats, Targets};
use sph_kernels::Kernel;
use sph_tree::{BoundingBox, CompactNeighborList, NeighborStats};
use std::ops::Range;

impl<K: Kernel, C: Communicator> Hydro<K, C> {
    /// The IAD matrices of the owned particles, with volumes `m / rho` or
    /// the volume elements `X / k`.
    ///
    /// With `divergence` the velocity divergence (and the curl, for the
    /// Balsara limiter) of the owned particles is computed in the same pass.
    pub(super) fn iad(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        divergence: bool,
    ) -> Result<(), CoreError> {
        if divergence {
            self.size_gradient(p.len());
        }
        let pos = positions!(p);
        let volumes = match self.config.scheme.volume {
            Volume::Mass => [&p.m[..], &p.rho[..]],
            Volume::Generalised | Volume::PressureEnergy => [&self.buf.xm[..], &self.buf.kx[..]],
        };
        let result = if divergence {
            let n = p.len();
            self.buf.div_v.resize(n, 0.0);
            if self.config.scheme.balsara {
                self.buf.curl_v.resize(n, 0.0);
            }
            let flow = FlowState {
                pos,
                vx: &p.vx,
                vy: &p.vy,
                vz: &p.vz,
                rho: &p.rho,
                c: &p.c,
                iad: [&[]; 6],
            };
            iad_and_velocity_divergence(
                &self.kernel,
                bbox,
                flow,
                volumes,
                &self.list,
                &mut p.iad,
                &mut self.buf.div_v,
                &mut self.buf.curl_v,
                &mut self.buf.grad_v,
            )
        } else {
            iad_volumes(&self.kernel, bbox, pos, volumes, &self.list, &mut p.iad)
        };
        result.map_err(|s| CoreError::SingularIad {
            step,
            id: p.id[s.index],
            det: s.det,
            neighbors: self.list.count(s.index),
        })
    }

    /// The viscosity switches and the Balsara limiter: velocity divergence
    /// (and curl, for the limiter), exchanged to the halos when the
    /// switches need it, then alpha advanced over the time since its last
    /// update (none before step 1); the strengths the momentum stage reads
    /// (`alpha`, or `alpha_eff` with the limiter) are exchanged too.
    pub(super) fn switches(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        clock: &mut StageClock,
        divergence_done: bool,
    ) -> Result<(), CoreError> {
        let scheme = self.config.scheme;
        let n = p.len();
        let g = scheme.gradients;
        if !divergence_done {
            self.size_gradient(n);
        }
        let (kernel, list) = (&self.kernel, &self.list);
        if !divergence_done {
            self.buf.div_v.resize(n, 0.0);
            if scheme.balsara {
                self.buf.curl_v.resize(n, 0.0);
            }
            let flow = FlowState::from(hydro_state!(p));
            velocity_divergence(
                kernel,
                bbox,
                flow,
                g,
                list,
                &mut self.buf.div_v,
                &mut self.buf.curl_v,
                &mut self.buf.grad_v,
            );
            clock.lap(Stage::Switches);
        }
        if let Some(sw) = scheme.switches() {
            self.domain.exchange(&mut [self.buf.div_v.as_mut_slice()])?;
            clock.lap(Stage::Halos);
            // Each particle's own step under block time steps.
            let elapsed = if self.config.time_steps.on_time_line() {
                Elapsed::PerParticle(self.block.elapsed())
            } else {
                Elapsed::Uniform(if step == 1 { 0.0 } else { self.dt_prev })
            };
            let flow = FlowState::from(hydro_state!(p));
            update_alpha_over(
                kernel,
                bbox,
                flow,
                g,
                &self.buf.div_v,
                &sw,
                elapsed,
                list,
                &mut p.alpha,
            );
            clock.lap(Stage::Switches);
        }
        if scheme.balsara {
            self.buf.alpha_eff.resize(n, 0.0);
            let constant = scheme.alpha();
            let switched = scheme.switches().is_some();
            // The served targets: inactive particles hold theirs under
            // block time steps.
            for i in list.served_targets() {
                let base = if switched { p.alpha[i] } else { constant };
                let f = balsara(self.buf.div_v[i], self.buf.curl_v[i], p.c[i], p.h[i]);
                self.buf.alpha_eff[i] = base * f;
            }
            clock.lap(Stage::Switches);
            self.domain
                .exchange(&mut [self.buf.alpha_eff.as_mut_slice()])?;
        } else if scheme.switches().is_some() {
            self.domain.exchange(&mut [p.alpha.as_mut_slice()])?;
        }
        if scheme.av_cleaning {
            let mut fields: Vec<&mut [f64]> =
                self.buf.grad_v.iter_mut().map(Vec::as_mut_slice).collect();
            self.domain.exchange(&mut fields)?;
        }
        clock.lap(Stage::Halos);
        Ok(())
    }

    /// Sizes the six symmetric-gradient fields to `n` particles when the
    /// scheme cleans the viscosity (none otherwise).
    pub(super) fn size_gradient(&mut self, n: usize) {
        if self.config.scheme.av_cleaning {
            self.buf.grad_v.resize_with(6, Vec::new);
            for v in &mut self.buf.grad_v {
                v.resize(n, 0.0);
            }
        }
    }

    /// Accelerations and du/dt of the owned particles, with the scheme's
    /// viscosity and volumes.
    pub(super) fn momentum(&mut self, p: &mut Particles, bbox: &BoundingBox) -> MomentumStats {
        let n = p.len();
        let state = hydro_state!(p);
        let (hv, comp) = (&mut self.buf.h_over_vsig, &mut self.buf.compression);
        let block = self.config.time_steps.on_time_line();
        let criteria = (self.config.bin_report || block).then(|| {
            hv.resize(n, 0.0);
            comp.resize(n, 0.0);
            Criteria {
                h_over_vsig: hv,
                compression: comp,
            }
        });
        // On the time line the conduction is exchanged as impulses
        // (`block_conduction.rs`), outside `du`.
        let imp = &mut self.impulses;
        let (weights, impulse) = if block && self.config.scheme.conductivity.is_some() {
            let w = ImpulseWeights {
                since: &imp.since,
                starts: &imp.starts,
                gains: &imp.gains,
                inv_quantum: imp.inv_quantum,
            };
            (Some(w), Some(imp.du.as_mut_slice()))
        } else {
            (None, None)
        };
        let rates = Rates {
            ax: &mut p.ax,
            ay: &mut p.ay,
            az: &mut p.az,
            du: &mut p.du,
            criteria,
            impulse,
        };
        let s = self.config.scheme;
        let alpha = if s.balsara {
            Alpha::PerParticle(&self.buf.alpha_eff)
        } else {
            match s.viscosity {
                Viscosity::Constant { alpha } => Alpha::Constant(alpha),
                Viscosity::Switched(_) => Alpha::PerParticle(&p.alpha),
            }
        };
        let scheme = MomentumScheme {
            gradients: s.gradients,
            alpha,
            av_form: s.av_form,
            volumes: VolumeWeights::of(s.volume, &self.buf.xm),
            cleaning: s.av_cleaning.then(|| AvCleaning {
                grad_v: std::array::from_fn(|k| self.buf.grad_v[k].as_slice()),
                eta_crit: AvCleaning::eta_crit(self.config.neighbors.ng0),
            }),
            stress: s
                .artificial_stress
                .map(|e| ArtificialStress::new(e, self.config.neighbors.ng0, &self.kernel)),
            conduction: s.conductivity.map(|alpha_u| Conductivity {
                alpha_u,
                p: &p.p,
                u: &p.u,
                contrast: s.conduction_contrast,
                impulses: weights,
            }),
        };
        let (k, f, list) = (&self.kernel, &self.buf.factors, &self.list);
        momentum_energy_with(k, bbox, state, f, scheme, list, rates)
    }

    /// [`StepReport::bins`](super::StepReport::bins) of the step `dt` just
    /// chosen: each owned particle's own step from the momentum stage's
    /// criteria, its |a| where the acceleration criterion is on (gravity)
    /// and its cooling rate where the pressure depends on `u` (`energy`),
    /// counted by `floor(log2(dt_i / dt))`, over all ranks.
    pub(super) fn bin_counts(
        &self,
        p: &Particles,
        owned: Range<usize>,
        dt: f64,
        energy: bool,
    ) -> [u64; BIN_OFFSETS] {
        let ts = &self.config.timestep;
        let (hv, comp) = (&self.buf.h_over_vsig, &self.buf.compression);
        let criterion = self.acc_criterion();
        let mut counts = owned
            .into_par_iter()
            .map(|i| {
                let acc = criterion.at(p, i);
                let cooling = cooling_rate(p, i, energy);
                let own = ts.particle_dt(hv[i], comp[i], acc, cooling);
                // The global step is at most every particle's: k >= 0.
                let k = (own / dt).log2().floor();
                if k >= (BIN_OFFSETS - 1) as f64 {
                    BIN_OFFSETS - 1
                } else if k >= 0.0 {
                    k as usize
                } else {
                    0
                }
            })
            .fold(
                || [0u64; BIN_OFFSETS],
                |mut c, k| {
                    c[k] += 1;
                    c
                },
            )
            .reduce(
                || [0u64; BIN_OFFSETS],
                |a, b| std::array::from_fn(|k| a[k] + b[k]),
            );
        self.domain.comm().all_reduce(&mut counts, ReduceOp::Sum);
        counts
    }

    /// What the acceleration criterion reads per particle (off without
    /// gravity).
    pub(super) fn acc_criterion(&self) -> AccCriterion {
        AccCriterion {
            softening: self.gravity.as_ref().map(|g| g.params().softening),
            timestep: self.config.timestep,
        }
    }

    /// Adds self-gravity to the owned `targets`' accelerations (when the
    /// run has it).
    pub(super) fn add_gravity(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        targets: Targets<'_>,
        step: u64,
    ) -> Result<(), CoreError> {
        if self.gravity.is_none() {
            return Ok(());
        }
        self.gravity_field(p, bbox, owned.clone(), targets, step)?;
        let f = &self.field;
        for (k, i) in owned.clone().enumerate() {
            if targets.is_active(k) {
                p.ax[i] += f.ax[k];
                p.ay[i] += f.ay[k];
                p.az[i] += f.az[k];
            }
        }
        Ok(())
    }

    /// Over the owned particles: `[max_k |v_n,k|, max_k |a_k|, max h_next,
    /// max -du/dt / u]` with `v_n = dX / dt_prev + a dt_prev / 2` (the
    /// Press velocity the integrator will use), `h_next = h * factor(nc)`
    /// (its h update) and the cooling rate over particles with `u > 0` and
    /// falling (0 unless `energy`: the pressure depends on `u`).
    pub(super) fn motion_bounds(
        &self,
        p: &Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        hu: HUpdate,
        energy: bool,
    ) -> [f64; 4] {
        let any_open = (0..3).any(|k| !bbox.is_periodic(k));
        let half = 0.5 * self.dt_prev;
        let inv = 1.0 / self.dt_prev;
        owned
            .into_par_iter()
            .map(|i| {
                let h_next = p.h[i] * hu.factor(p.nc[i]);
                let cooling = cooling_rate(p, i, energy);
                if !any_open {
                    return [0.0, 0.0, h_next, cooling];
                }
                let a = [p.ax[i].abs(), p.ay[i].abs(), p.az[i].abs()];
                let d = [p.dx[i].abs(), p.dy[i].abs(), p.dz[i].abs()];
                let v = (0..3).map(|k| d[k] * inv + a[k] * half).fold(0.0, f64::max);
                [v, a[0].max(a[1]).max(a[2]), h_next, cooling]
            })
            .reduce(|| [0.0; 4], |x, y| std::array::from_fn(|k| x[k].max(y[k])))
    }

    /// Evaluates the self-gravity of all particles on the owned `targets`
    /// (flags and drift relative to the owned range; into the gravity
    /// field buffer) and stores their potential in `phi`. `bbox` is the
    /// box the domain's keys were computed in.
    pub(super) fn gravity_field(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        owned: Range<usize>,
        targets: Targets<'_>,
        step: u64,
    ) -> Result<GravityStats, CoreError> {
        let Some(solver) = self.gravity.as_mut() else {
            return Ok(GravityStats::default());
        };
        if p.phi.len() != p.len() {
            return Err(CoreError::Invalid(
                "self-gravity needs the potential field: build the particles with FieldSet { gravity: true, .. }".into(),
            ));
        }
        // The gravity tree holds the owned particles only (halos are
        // copies); on one rank that is the neighbour tree itself.
        let r = owned.clone();
        let tree = if owned.len() == p.len() {
            &self.tree
        } else {
            self.gravity_tree.rebuild(
                &self.domain.keys()[r.clone()],
                &p.x[r.clone()],
                &p.y[r.clone()],
                &p.z[r.clone()],
                self.config.bucket,
            )?;
            &self.gravity_tree
        };
        let dec = Decomposition {
            bbox,
            curve: self.config.curve,
            key_start: self.domain.key_ranges(),
            h_max: self.domain.h_limit(),
        };
        let stats = solver
            .compute(
                self.domain.comm(),
                dec,
                tree,
                &p.x[r.clone()],
                &p.y[r.clone()],
                &p.z[r.clone()],
                &p.m[r.clone()],
                Some(&p.h[r.clone()]),
                targets,
                &mut self.field,
            )
            .map_err(|source| CoreError::Gravity { step, source })?;
        match targets.active {
            None => p.phi[owned].copy_from_slice(&self.field.phi),
            Some(active) => {
                for (k, i) in owned.enumerate().filter(|&(k, _)| active[k]) {
                    p.phi[i] = self.field.phi[k];
                }
            }
        }
        Ok(stats)
    }

    /// Neighbour lists of the owned particles, with the h iteration. Counts
    /// are one-sided (`r < 2 h_i`), so each particle's iteration is its own
    /// business; the lists are symmetric (`r < 2 max(h_i, h_j)`), so once
    /// the halos' final h are known the lists are rebuilt if any changed.
    pub(super) fn search(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
        step: u64,
        owned: Range<usize>,
        active: Option<&[bool]>,
    ) -> Result<NeighborStats, CoreError> {
        let h_limit = self.domain.h_limit();
        let params = if self.config.scheme.fixed_h {
            self.config.neighbors.without_iteration()
        } else {
            self.config.neighbors
        };
        let run = |p: &mut Particles, list: &mut CompactNeighborList| {
            find_neighbors_of(
                &params,
                self.config.h_update,
                &self.tree,
                bbox,
                [&p.x, &p.y, &p.z],
                &mut p.h,
                &p.id,
                owned.clone(),
                active,
                h_limit,
                list,
                &mut p.nc,
                step,
            )
        };
        let stats = run(p, &mut self.list)?;
        if self.domain.comm().size() == 1 {
            return Ok(stats);
        }
        // Only halos change in the exchange: keep their h alone.
        let halos = |h: &[f64]| {
            let (low, rest) = h.split_at(owned.start);
            low.iter()
                .chain(&rest[owned.len()..])
                .map(|v| v.to_bits())
                .collect::<Vec<u64>>()
        };
        let before = halos(&p.h);
        self.domain.exchange(&mut [p.h.as_mut_slice()])?;
        let changed = before != halos(&p.h);
        // Every rank's lists must see every particle's final h.
        if changed {
            return run(p, &mut self.list);
        }
        Ok(stats)
    }

    /// Density and grad-h factor of the owned particles; with generalised
    /// volumes, `X` (exchanged to the halos), then `k`, the density
    /// `k m / X` and the grad-h factor.
    pub(super) fn density(
        &mut self,
        p: &mut Particles,
        bbox: &BoundingBox,
    ) -> Result<(), CoreError> {
        let pos = positions!(p);
        if self.config.scheme.volume == Volume::Mass {
            density(
                &self.kernel,
                bbox,
                pos,
                &self.list,
                &mut p.rho,
                &mut p.omega,
            );
            return Ok(());
        }
        let n = p.len();
        self.buf.xm.resize(n, 0.0);
        self.buf.kx.resize(n, 0.0);
        if self.config.scheme.volume == Volume::PressureEnergy {
            // X = m u, halos included (their u came with them).
            for ((x, m), u) in self.buf.xm.iter_mut().zip(&p.m).zip(&p.u) {
                *x = m * u;
            }
        } else {
            xmass(&self.kernel, bbox, pos, &self.list, &mut self.buf.xm);
            self.domain.exchange(&mut [self.buf.xm.as_mut_slice()])?;
        }
        // A volume element of 0 (a massless particle, or cold gas under
        // pressure-energy volumes) would make its density 0 / 0.
        if let Some(i) = self
            .buf
            .xm
            .iter()
            .position(|&x| !(x > 0.0 && x.is_finite()))
        {
            return Err(CoreError::Invalid(
                if self.config.scheme.volume == Volume::PressureEnergy {
                    format!(
                        "pressure-energy volumes need m u > 0: particle id {} has m = {}, u = {} (use --volume mass or ve for cold gas)",
                        p.id[i], p.m[i], p.u[i]
                    )
                } else {
                    format!(
                        "generalised volume elements need m > 0: particle id {} has m = {} (use --volume mass for massless particles)",
                        p.id[i], p.m[i]
                    )
                },
            ));
        }
        let out = VeOut {
            kx: &mut self.buf.kx,
            rho: &mut p.rho,
            omega: &mut p.omega,
        };
        let density_of_elements = if self.config.scheme.volume == Volume::PressureEnergy {
            pressure_energy_density::<K>
        } else {
            ve_density::<K>
        };
        let (kernel, xm, list) = (&self.kernel, &self.buf.xm, &self.list);
        density_of_elements(kernel, bbox, positions!(p), xm, list, out);
        Ok(())
    }

    /// Sends the owners' density, pressure, sound speed (and Omega) to the
    /// halos.
    pub(super) fn exchange_thermo(&mut self, p: &mut Particles) -> Result<(), CoreError> {
        let mut fields: Vec<&mut [f64]> = vec![&mut p.rho, &mut p.p, &mut p.c];
        if !p.omega.is_empty() {
            fields.push(&mut p.omega);
        }
        if self.config.scheme.volume != Volume::Mass {
            fields.push(&mut self.buf.kx);
        }
        self.domain.exchange(&mut fields)?;
        Ok(())
    }

    /// Pressure and sound speed of the owned particles; an EOS with a
    /// per-particle reference state calibrates reference densities left at
    /// zero to the current density.
    pub(super) fn eos(&self, p: &mut Particles, owned: Range<usize>) -> Result<(), CoreError> {
        let r = owned;
        let reference = if self.config.eos.needs_reference() {
            // The field table's check at the start of `step` and
            // `evaluate_density` (HydroConfig::fields holds eos_ref) made
            // sure the reference state is there.
            for i in r.clone() {
                if p.eos_ref[0][i] == 0.0 {
                    p.eos_ref[0][i] = p.rho[i];
                }
            }
            Some((&p.eos_ref[0][r.clone()], &p.eos_ref[1][r.clone()]))
        } else {
            None
        };
        self.config.eos.apply(
            &p.rho[r.clone()],
            &p.u[r.clone()],
            reference,
            &mut p.p[r.clone()],
            &mut p.c[r],
        );
        Ok(())
    }

    /// At a run's first step, a barotropic EOS (isothermal, polytropic)
    /// sets each owned particle's `u` to the compression energy of its
    /// density ([`Eos::energy`](crate::Eos::energy)), so that `E_int` means
    /// something and `u - e(rho)` is the heat made since. A restart starts
    /// past step 1 and keeps the stored `u`.
    pub(super) fn calibrate_energy(&self, p: &mut Particles, owned: Range<usize>) {
        let eos = self.config.eos;
        if eos.energy(1.0).is_none() {
            return;
        }
        p.u[owned.clone()]
            .par_iter_mut()
            .zip(p.rho[owned].par_iter())
            .for_each(|(u, &rho)| *u = eos.energy(rho).unwrap_or(*u));
    }
}

/// The acceleration criterion's input per particle.
#[derive(Debug, Clone, Copy)]
pub(super) struct AccCriterion {
    /// The gravity's softening scale `s`; `None` without gravity.
    softening: Option<f64>,
    timestep: TimestepParams,
}

impl AccCriterion {
    /// What particle `i`'s acceleration criterion reads, `|a_i| / eps_i`
    /// ([`TimestepParams::acc_per_length`]; 0 without gravity: the
    /// criterion is off). `eps_i = 2 s h_i`, the softening length of a
    /// pair of particles like `i` (pairs are softened within
    /// `s (h_i + h_j)`), so the criterion follows each particle's
    /// resolution; the fixed length where `s = 0`.
    pub(super) fn at(&self, p: &Particles, i: usize) -> f64 {
        let Some(scale) = self.softening else {
            return 0.0;
        };
        let acc = (p.ax[i] * p.ax[i] + p.ay[i] * p.ay[i] + p.az[i] * p.az[i]).sqrt();
        let eps = (scale > 0.0).then(|| 2.0 * scale * p.h[i]);
        self.timestep.acc_per_length(acc, eps)
    }
}

/// Particle `i`'s cooling rate `-du/dt / u` for the energy criterion: 0
/// unless `energy` (the pressure reads `u`; only then are the fields read)
/// and `u > 0` is falling.
#[inline]
pub(super) fn cooling_rate(p: &Particles, i: usize, energy: bool) -> f64 {
    if energy && p.u[i] > 0.0 && p.du[i] < 0.0 {
        -p.du[i] / p.u[i]
    } else {
        0.0
    }
}
