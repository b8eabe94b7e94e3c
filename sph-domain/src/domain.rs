//! The distributed domain: one `sync` per step puts every rank's particles
//! in global SFC order (migration to the owners of balanced key ranges) and
//! appends the halos its owned particles interact with; `exchange` then
//! refreshes any halo fields point to point, `exchange_where` those of a
//! subset of the owned particles, and `exchange_reverse_min` takes halo
//! values back to their owners, keeping the minimum.

use crate::global_tree::{Assignment, GlobalTree};
use crate::halo::candidate_cells;
use crate::{halo_slot, DomainError, ParticleFields};
use rayon::prelude::*;
use sph_comm::{Communicator, Plain, ReduceOp};
use sph_tree::{compute_keys, Boundary, BoundingBox, Curve, KeySorter};
use std::ops::Range;
use std::time::Instant;

/// Parameters of the decomposition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DomainConfig {
    /// Space-filling curve of the keys.
    pub curve: Curve,
    /// Most particles per global-tree leaf (cornerstone's `globalBucketSize`);
    /// leaves are the unit of load balance and of halo discovery.
    pub bucket: u64,
    /// Headroom of the interaction radius over the largest smoothing length
    /// at sync time: halos cover `2 * margin * h_max`, so smoothing lengths
    /// may grow by this factor during the step's h iteration.
    pub h_margin: f64,
}

impl Default for DomainConfig {
    fn default() -> Self {
        Self {
            curve: Curve::Hilbert,
            bucket: 256,
            h_margin: 1.2,
        }
    }
}

/// Figures of the last [`Domain::sync`] and the exchanges since.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SyncStats {
    /// Particles owned by this rank.
    pub owned: usize,
    /// Halo particles held by this rank.
    pub halos: usize,
    /// Particles that arrived by migration.
    pub migrated_in: usize,
    /// Bytes this rank sent (migration, halos and field exchanges).
    pub bytes_sent: u64,
    /// Seconds spent inside communication calls.
    pub comm_seconds: f64,
    /// Seconds of the whole sync, communication included.
    pub sync_seconds: f64,
}

/// Halo exchange plan for one peer.
#[derive(Debug, Clone, Default)]
struct Peer {
    rank: usize,
    /// Local indices of owned particles this rank sends to the peer.
    send: Vec<u32>,
    /// Local indices of the halos the peer sends to this rank, in its order.
    recv: Vec<u32>,
}

/// A rank's view of the distributed particle set.
#[derive(Debug)]
pub struct Domain<C: Communicator> {
    comm: C,
    config: DomainConfig,
    tree: GlobalTree,
    counts: Vec<u64>,
    assignment: Assignment,
    keys: Vec<u64>,
    perm: Vec<u32>,
    scratch: Vec<u64>,
    scratch_keys: Vec<u64>,
    owned: Option<Range<usize>>,
    peers: Vec<Peer>,
    h_limit: f64,
    stats: SyncStats,
}

impl<C: Communicator> Domain<C> {
    /// A domain over `comm`. The first [`sync`](Self::sync) takes every
    /// particle a rank holds as its own.
    pub fn new(comm: C, config: DomainConfig) -> Result<Self, DomainError> {
        if config.bucket == 0 {
            return Err(DomainError::InvalidBucket(config.bucket));
        }
        if !(config.h_margin >= 1.0 && config.h_margin.is_finite()) {
            return Err(DomainError::InvalidHMargin(config.h_margin));
        }
        Ok(Self {
            comm,
            config,
            tree: GlobalTree::uniform(1),
            counts: Vec::new(),
            assignment: Assignment::default(),
            keys: Vec::new(),
            perm: Vec::new(),
            scratch: Vec::new(),
            scratch_keys: Vec::new(),
            owned: None,
            peers: Vec::new(),
            h_limit: f64::INFINITY,
            stats: SyncStats::default(),
        })
    }

    /// The communicator.
    pub fn comm(&self) -> &C {
        &self.comm
    }

    /// Whether the buffers rebuilt every step are freed between steps: on
    /// several ranks, where the sync's halo messages then reuse their
    /// memory instead of adding to the peak (the sort's buffers here,
    /// `Hydro`'s neighbour lists, trees and pair factors; measured, Sedov
    /// 80^3 on 2 ranks: 5 MiB of the sort, 15 MiB of the rest per rank);
    /// not on one rank, which has no halo messages and where re-faulting the
    /// pages costs 4-5% of a step.
    pub fn releases_step_buffers(&self) -> bool {
        self.comm.size() > 1
    }

    /// The decomposition parameters.
    pub fn config(&self) -> &DomainConfig {
        &self.config
    }

    /// Range of the owned particles in the local arrays (after a sync).
    pub fn owned(&self) -> Range<usize> {
        self.owned.clone().unwrap_or(0..0)
    }

    /// SFC keys of the local arrays (halos and owned), ascending.
    pub fn keys(&self) -> &[u64] {
        &self.keys
    }

    /// The largest smoothing length the halos of this sync cover
    /// (`h_margin` times the global maximum at sync time; the same on
    /// every rank).
    pub fn h_limit(&self) -> f64 {
        self.h_limit
    }

    /// Figures of the last sync and the exchanges since.
    pub fn stats(&self) -> SyncStats {
        self.stats
    }

    /// The global tree (replicated on every rank).
    pub fn global_tree(&self) -> &GlobalTree {
        &self.tree
    }

    /// First key owned by each rank, then the end of the key space.
    pub fn key_ranges(&self) -> &[u64] {
        &self.assignment.key_start
    }

    /// Brings the particles into global curve order: refits the open axes of
    /// `bbox` to all ranks' particles, migrates every particle to the rank
    /// owning its key and appends the halos. Afterwards the local arrays hold
    /// halos and owned particles in ascending (key, id) order; the owned ones
    /// are [`owned`](Self::owned). Two global reductions: the box with the
    /// largest h, and the tree counts.
    pub fn sync<P: ParticleFields>(
        &mut self,
        p: &mut P,
        bbox: &mut BoundingBox,
    ) -> Result<Range<usize>, DomainError> {
        self.sync_with(p, bbox, None)
    }

    /// [`sync`](Self::sync) when the caller already knows, identically on
    /// every rank, a box holding every particle (its open axes are kept as
    /// given) and the largest smoothing length: then the tree counts are the
    /// only global reduction. A solver can carry both from its time-step
    /// reduction (bounding how far particles can move in one step).
    /// Particles outside an open axis of `bbox` are an error.
    pub fn sync_with<P: ParticleFields>(
        &mut self,
        p: &mut P,
        bbox: &mut BoundingBox,
        h_max: Option<f64>,
    ) -> Result<Range<usize>, DomainError> {
        let start = Instant::now();
        let mut comm_s = 0.0;
        let mut bytes = 0u64;
        if let Some(owned) = self.owned.take() {
            p.keep(owned);
        }
        self.peers.clear();

        match h_max {
            Some(h) => {
                check_inside(p, bbox)?;
                self.h_limit = h * self.config.h_margin;
            }
            None => {
                // Global box and largest h: one max-reduction.
                let mut ext = local_extent(p)?;
                let t = Instant::now();
                self.comm.all_reduce(&mut ext, ReduceOp::Max);
                comm_s += t.elapsed().as_secs_f64();
                if ext[6] == f64::NEG_INFINITY {
                    return Err(DomainError::Empty);
                }
                refit(bbox, &ext)?;
                self.h_limit = ext[6] * self.config.h_margin;
            }
        }

        // Local curve order, then global counts: one sum-reduction.
        self.sort_local(p, bbox);
        self.tree.count(&self.keys, &mut self.counts);
        let t = Instant::now();
        self.comm.all_reduce(&mut self.counts, ReduceOp::Sum);
        comm_s += t.elapsed().as_secs_f64();
        let ranks = self.comm.size();
        let rank = self.comm.rank();
        self.assignment = Assignment::balanced(&self.tree, &self.counts, ranks);

        // Migration: the particles outside this rank's key range go to
        // their owners; sorted keys make them a prefix and a suffix.
        let (klo, khi) = (
            self.assignment.key_start[rank],
            self.assignment.key_start[rank + 1],
        );
        let lo = self.keys.partition_point(|&k| k < klo);
        let hi = self.keys.partition_point(|&k| k < khi);
        let mut migrated_in = 0;
        if ranks > 1 {
            let words = p.packed_words();
            let mut sends: Vec<(usize, Vec<u64>)> = Vec::new();
            for i in (0..lo).chain(hi..p.len()) {
                let owner = self.assignment.owner(self.keys[i]);
                match sends.last_mut() {
                    Some((r, buf)) if *r == owner => p.pack(i, buf),
                    _ => {
                        let mut buf = Vec::new();
                        p.pack(i, &mut buf);
                        sends.push((owner, buf));
                    }
                }
            }
            bytes += sends.iter().map(|(_, b)| b.len() as u64 * 8).sum::<u64>();
            let t = Instant::now();
            let received = self.comm.sparse_exchange(&sends)?;
            comm_s += t.elapsed().as_secs_f64();
            // Buffers go as soon as they are used: the peak memory of a
            // step is reached here.
            drop(sends);
            p.keep(lo..hi);
            p.reserve(received.iter().map(|(_, b)| b.len() / words.max(1)).sum());
            for (_, buf) in received {
                for chunk in buf.chunks_exact(words) {
                    p.push_packed(chunk);
                    migrated_in += 1;
                }
            }
            if migrated_in > 0 {
                self.sort_local(p, bbox);
            } else {
                self.keys.drain(hi..);
                self.keys.drain(..lo);
            }
        }
        let n_owned = p.len();

        // Halos: this rank's particles within reach of another rank's cells.
        let mut n_low = 0;
        if ranks > 1 {
            let radius = 2.0 * self.h_limit;
            let (sends, plan) = self.find_halos(p, bbox, rank, radius);
            bytes += sends.iter().map(|(_, b)| b.len() as u64 * 8).sum::<u64>();
            let t = Instant::now();
            let received = self.comm.sparse_exchange(&sends)?;
            comm_s += t.elapsed().as_secs_f64();
            drop(sends);
            let words = p.halo_words();
            let mut recv_ranks = Vec::with_capacity(received.len());
            p.reserve(received.iter().map(|(_, b)| b.len() / words.max(1)).sum());
            for (r, buf) in received {
                if buf.len() % words.max(1) != 0 {
                    return Err(DomainError::Mismatch {
                        peer: r,
                        expected: buf.len() - buf.len() % words.max(1),
                        got: buf.len(),
                    });
                }
                recv_ranks.push((r, buf.len() / words.max(1)));
                p.push_halos(&buf);
            }
            n_low = self.place_halos(p, bbox, n_owned, klo);
            // Halo slots: the k-th halo received sits where the sort put it.
            let mut next = n_owned;
            let mut peers: Vec<Peer> = plan
                .into_iter()
                .map(|(r, send)| Peer {
                    rank: r,
                    send: send.into_iter().map(|i| i + n_low as u32).collect(),
                    recv: Vec::new(),
                })
                .collect();
            for (r, count) in recv_ranks {
                let slots: Vec<u32> = (next..next + count)
                    .map(|old| self.scratch_keys[old - n_owned] as u32)
                    .collect();
                next += count;
                match peers.iter_mut().find(|q| q.rank == r) {
                    Some(q) => q.recv = slots,
                    None => peers.push(Peer {
                        rank: r,
                        send: Vec::new(),
                        recv: slots,
                    }),
                }
            }
            peers.sort_by_key(|q| q.rank);
            self.peers = peers;
        }

        if self.releases_step_buffers() {
            for v in [&mut self.scratch, &mut self.scratch_keys] {
                *v = Vec::new();
            }
            self.perm = Vec::new();
        }

        // The tree follows the particles: refine/coarsen for the next step.
        self.tree.rebalance(&self.counts, self.config.bucket);
        let owned = n_low..n_low + n_owned;
        self.owned = Some(owned.clone());
        self.stats = SyncStats {
            owned: n_owned,
            halos: p.len() - n_owned,
            migrated_in,
            bytes_sent: bytes,
            comm_seconds: comm_s,
            sync_seconds: start.elapsed().as_secs_f64(),
        };
        Ok(owned)
    }

    /// Copies the owners' values of `fields` into the halo slots of every
    /// rank (point to point, with the peers of the last sync). Collective:
    /// every rank calls it, also one without peers (the sparse exchange
    /// needs every rank to learn that nothing more is coming).
    pub fn exchange(&mut self, fields: &mut [&mut [f64]]) -> Result<(), DomainError> {
        if self.comm.size() == 1 {
            return Ok(());
        }
        let nf = fields.len();
        let sends: Vec<(usize, Vec<f64>)> = self
            .peers
            .iter()
            .filter(|q| !q.send.is_empty())
            .map(|q| {
                let mut buf = Vec::with_capacity(q.send.len() * nf);
                for &i in &q.send {
                    buf.extend(fields.iter().map(|f| f[i as usize]));
                }
                (q.rank, buf)
            })
            .collect();
        self.stats.bytes_sent += sends.iter().map(|(_, b)| b.len() as u64 * 8).sum::<u64>();
        let t = Instant::now();
        let received = self.comm.sparse_exchange(&sends)?;
        self.stats.comm_seconds += t.elapsed().as_secs_f64();
        for (r, buf) in received {
            let peer = self
                .peers
                .iter()
                .find(|q| q.rank == r)
                .ok_or(DomainError::UnexpectedPeer(r))?;
            if buf.len() != peer.recv.len() * nf {
                return Err(DomainError::Mismatch {
                    peer: r,
                    expected: peer.recv.len() * nf,
                    got: buf.len(),
                });
            }
            for (k, &slot) in peer.recv.iter().enumerate() {
                for (f, field) in fields.iter_mut().enumerate() {
                    field[slot as usize] = buf[k * nf + f];
                }
            }
        }
        Ok(())
    }

    /// [`exchange`](Self::exchange) for a subset: copies the owners' values
    /// of `fields` into the halo slots of the owned particles `i` (local
    /// indices) with `send(i)` true, and leaves every other halo slot as it
    /// is. Collective, like `exchange`.
    ///
    /// Only the owner decides what travels: a message holds, per particle
    /// sent, its position in the sender's halo list for the receiving rank
    /// (which the receiver maps to its halo slot through the plan of the
    /// last sync), then its values, so the receiver needs no prior
    /// knowledge of which particles come. Peers with nothing selected get
    /// no message. With `send` always true the halo slots receive exactly
    /// what `exchange` gives them (the same bits; `exchange` is cheaper, as
    /// it sends no indices). On one rank there are no halos (periodic
    /// images are folds, not copies) and nothing happens.
    ///
    /// `send` is called only with owned indices, twice for each peer the
    /// particle is a halo of (a count sizes each message, then the values
    /// are packed), so it must be a pure predicate (an activity flag, a
    /// time-bin test).
    ///
    /// # Errors
    /// [`DomainError::Comm`] if the exchange fails; [`DomainError::UnexpectedPeer`],
    /// [`DomainError::Mismatch`] or [`DomainError::HaloIndex`] for a message
    /// that does not fit the plan of the last sync (which ranks calling
    /// with different field counts also produce).
    ///
    /// # Panics
    /// If a field is shorter than the local arrays of the last sync.
    ///
    /// # Examples
    ///
    /// Two in-process ranks; only even ids are refreshed:
    ///
    /// ```
    /// use sph_comm::{run_ranks, Communicator};
    /// use sph_domain::{Domain, DomainConfig, Points};
    /// use sph_tree::{Boundary, BoundingBox};
    ///
    /// run_ranks(2, |comm| {
    ///     let mut cloud = Points::default();
    ///     for i in (comm.rank() as u64..1000).step_by(2) {
    ///         let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
    ///         cloud.push(i, [f(7), f(13), f(31)], 0.05);
    ///     }
    ///     let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    ///     let mut domain = Domain::new(&comm, DomainConfig::default()).unwrap();
    ///     let owned = domain.sync(&mut cloud, &mut bbox).unwrap();
    ///     // Owners hold their id, halos -1.
    ///     let mut q: Vec<f64> = (0..cloud.id.len())
    ///         .map(|i| if owned.contains(&i) { cloud.id[i] as f64 } else { -1.0 })
    ///         .collect();
    ///     let ids = &cloud.id;
    ///     domain
    ///         .exchange_where(&mut [q.as_mut_slice()], |i| ids[i] % 2 == 0)
    ///         .unwrap();
    ///     for i in (0..ids.len()).filter(|i| !owned.contains(i)) {
    ///         let want = if ids[i] % 2 == 0 { ids[i] as f64 } else { -1.0 };
    ///         assert_eq!(q[i], want);
    ///     }
    /// });
    /// ```
    ///
    /// On one rank it does nothing:
    ///
    /// ```
    /// use sph_comm::SerialComm;
    /// use sph_domain::{Domain, DomainConfig, Points};
    /// use sph_tree::{Boundary, BoundingBox};
    ///
    /// let mut cloud = Points::default();
    /// for i in 0..100u64 {
    ///     cloud.push(i, [(i % 10) as f64 / 10.0, (i / 10) as f64 / 10.0, 0.5], 0.1);
    /// }
    /// let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    /// let mut domain = Domain::new(SerialComm::new(), DomainConfig::default()).unwrap();
    /// domain.sync(&mut cloud, &mut bbox).unwrap();
    /// let mut q = vec![1.0; 100];
    /// domain.exchange_where(&mut [q.as_mut_slice()], |_| true).unwrap();
    /// assert_eq!(q, vec![1.0; 100]);
    /// ```
    pub fn exchange_where(
        &mut self,
        fields: &mut [&mut [f64]],
        send: impl Fn(usize) -> bool,
    ) -> Result<(), DomainError> {
        if self.comm.size() == 1 {
            return Ok(());
        }
        let nf = fields.len();
        // Per particle: its index in the peer's list, then its values.
        let words = nf + 1;
        let mut sends: Vec<(usize, Vec<u64>)> = Vec::new();
        for q in &self.peers {
            // Counted first, so the buffer is allocated once at its size.
            let count = q.send.iter().filter(|&&i| send(i as usize)).count();
            if count == 0 {
                continue;
            }
            let mut buf = Vec::with_capacity(count * words);
            for (k, &i) in q.send.iter().enumerate() {
                if send(i as usize) {
                    buf.push(k as u64);
                    buf.extend(fields.iter().map(|f| f[i as usize].to_bits()));
                }
            }
            sends.push((q.rank, buf));
        }
        self.stats.bytes_sent += sends.iter().map(|(_, b)| b.len() as u64 * 8).sum::<u64>();
        let t = Instant::now();
        let received = self.comm.sparse_exchange(&sends)?;
        self.stats.comm_seconds += t.elapsed().as_secs_f64();
        drop(sends);
        for (r, buf) in received {
            let peer = self
                .peers
                .iter()
                .find(|q| q.rank == r)
                .ok_or(DomainError::UnexpectedPeer(r))?;
            if buf.len() % words != 0 {
                return Err(DomainError::Mismatch {
                    peer: r,
                    expected: buf.len() - buf.len() % words,
                    got: buf.len(),
                });
            }
            for chunk in buf.chunks_exact(words) {
                let slot = usize::try_from(chunk[0])
                    .ok()
                    .and_then(|k| peer.recv.get(k))
                    .ok_or(DomainError::HaloIndex {
                        peer: r,
                        index: chunk[0],
                        halos: peer.recv.len(),
                    })?;
                for (field, &v) in fields.iter_mut().zip(&chunk[1..]) {
                    field[*slot as usize] = f64::from_bits(v);
                }
            }
        }
        Ok(())
    }

    /// The reverse of a halo exchange, reducing by the minimum: every rank
    /// sends the values in its halo slots of `field` back to their owners,
    /// and each owned particle keeps the minimum of its own value and the
    /// values of all its halo copies. Halo slots are left as they are.
    /// Collective, like [`exchange`](Self::exchange); a no-op on one rank.
    ///
    /// Made for requests written into neighbours, such as the smallest time
    /// bin a particle's neighbours allow it (block time steps' wake-up).
    /// Integer elements (`u8`, `u32`, `u64`, ...: `Ord`), so the result is
    /// the same whatever the order in which copies arrive. Each peer's
    /// message holds all its halos of this rank, in the order of the last
    /// sync's plan, so no indices travel.
    ///
    /// # Errors
    /// [`DomainError::Comm`] if the exchange fails; [`DomainError::UnexpectedPeer`]
    /// or [`DomainError::Mismatch`] for a message that does not fit the
    /// plan of the last sync.
    ///
    /// # Panics
    /// If `field` is shorter than the local arrays of the last sync.
    ///
    /// # Examples
    ///
    /// Two in-process ranks: owners hold 9, the halos of rank `r` hold
    /// `r + 1`; afterwards exactly the owned particles that are halos
    /// elsewhere are lowered, to the other rank's value:
    ///
    /// ```
    /// use sph_comm::{run_ranks, Communicator};
    /// use sph_domain::{Domain, DomainConfig, Points};
    /// use sph_tree::{Boundary, BoundingBox};
    ///
    /// let counts = run_ranks(2, |comm| {
    ///     let mut cloud = Points::default();
    ///     for i in (comm.rank() as u64..1000).step_by(2) {
    ///         let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
    ///         cloud.push(i, [f(7), f(13), f(31)], 0.05);
    ///     }
    ///     let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    ///     let mut domain = Domain::new(&comm, DomainConfig::default()).unwrap();
    ///     let owned = domain.sync(&mut cloud, &mut bbox).unwrap();
    ///     let halo = comm.rank() as u8 + 1;
    ///     let mut bins: Vec<u8> = (0..cloud.id.len())
    ///         .map(|i| if owned.contains(&i) { 9 } else { halo })
    ///         .collect();
    ///     domain.exchange_reverse_min(&mut bins).unwrap();
    ///     let other = (1 - comm.rank()) as u8 + 1;
    ///     assert!(bins[owned.clone()].iter().all(|&b| b == 9 || b == other));
    ///     let lowered = bins[owned.clone()].iter().filter(|&&b| b < 9).count();
    ///     (lowered, cloud.id.len() - owned.len())
    /// });
    /// // Each particle is a halo on at most the one other rank.
    /// let lowered: usize = counts.iter().map(|c| c.0).sum();
    /// let halos: usize = counts.iter().map(|c| c.1).sum();
    /// assert_eq!(lowered, halos);
    /// assert!(halos > 0);
    /// ```
    pub fn exchange_reverse_min<T: Plain + Ord>(
        &mut self,
        field: &mut [T],
    ) -> Result<(), DomainError> {
        self.exchange_reverse_with(field, |own, v| {
            if v < *own {
                *own = v;
            }
        })
    }

    /// As [`exchange_reverse_min`](Self::exchange_reverse_min), each
    /// owner combining the halos' values into its own with `combine`
    /// (peers in the order of their messages: `combine` must not depend
    /// on it, as a minimum or an integer sum does not). Collective.
    ///
    /// ```
    /// use sph_comm::{run_ranks, Communicator};
    /// use sph_domain::{Domain, DomainConfig, Points};
    /// use sph_tree::{Boundary, BoundingBox};
    ///
    /// // Every copy of a particle adds 1: each owner counts its copies.
    /// let sums = run_ranks(2, |comm| {
    ///     let mut cloud = Points::default();
    ///     for i in (comm.rank() as u64..1000).step_by(2) {
    ///         let f = |k: u64| ((i * k) % 1000) as f64 / 1000.0;
    ///         cloud.push(i, [f(7), f(13), f(31)], 0.05);
    ///     }
    ///     let mut bbox = BoundingBox::cube(0.0, 1.0, Boundary::Periodic).unwrap();
    ///     let mut domain = Domain::new(&comm, DomainConfig::default()).unwrap();
    ///     let owned = domain.sync(&mut cloud, &mut bbox).unwrap();
    ///     let mut copies = vec![1i64; cloud.id.len()];
    ///     domain.exchange_reverse_with(&mut copies, |own, v| *own += v).unwrap();
    ///     let owned_sum: i64 = copies[owned.clone()].iter().sum();
    ///     (owned_sum, cloud.id.len())
    /// });
    /// // Every local copy, owned or halo, is counted once on its owner.
    /// let counted: i64 = sums.iter().map(|s| s.0).sum();
    /// let copies: usize = sums.iter().map(|s| s.1).sum();
    /// assert_eq!(counted as usize, copies);
    /// ```
    pub fn exchange_reverse_with<T: Plain>(
        &mut self,
        field: &mut [T],
        combine: impl Fn(&mut T, T),
    ) -> Result<(), DomainError> {
        if self.comm.size() == 1 {
            return Ok(());
        }
        let sends: Vec<(usize, Vec<T>)> = self
            .peers
            .iter()
            .filter(|q| !q.recv.is_empty())
            .map(|q| (q.rank, q.recv.iter().map(|&s| field[s as usize]).collect()))
            .collect();
        self.stats.bytes_sent += sends
            .iter()
            .map(|(_, b)| (b.len() * std::mem::size_of::<T>()) as u64)
            .sum::<u64>();
        let t = Instant::now();
        let received = self.comm.sparse_exchange(&sends)?;
        self.stats.comm_seconds += t.elapsed().as_secs_f64();
        drop(sends);
        for (r, buf) in received {
            let peer = self
                .peers
                .iter()
                .find(|q| q.rank == r)
                .ok_or(DomainError::UnexpectedPeer(r))?;
            if buf.len() != peer.send.len() {
                return Err(DomainError::Mismatch {
                    peer: r,
                    expected: peer.send.len(),
                    got: buf.len(),
                });
            }
            for (&i, &v) in peer.send.iter().zip(buf.iter()) {
                combine(&mut field[i as usize], v);
            }
        }
        Ok(())
    }

    /// Computes keys, sorts by (key, id) and reorders the particles.
    fn sort_local<P: ParticleFields>(&mut self, p: &mut P, bbox: &BoundingBox) {
        let [x, y, z] = p.positions();
        compute_keys(bbox, self.config.curve, x, y, z, &mut self.keys);
        KeySorter::new().sort(&self.keys, Some(p.ids()), &mut self.perm);
        p.reorder_carried(&self.perm, &mut self.scratch);
        sph_tree::apply_permutation(&self.perm, &mut self.keys, &mut self.scratch_keys);
    }

    /// For each peer, the ascending local indices of the owned particles
    /// within `radius` of one of its cells, packed for sending.
    #[allow(clippy::type_complexity)]
    fn find_halos<P: ParticleFields>(
        &self,
        p: &P,
        bbox: &BoundingBox,
        rank: usize,
        radius: f64,
    ) -> (Vec<(usize, Vec<u64>)>, Vec<(usize, Vec<u32>)>) {
        let a = &self.assignment;
        let curve = self.config.curve;
        let mine = a.leaf_start[rank]..a.leaf_start[rank + 1];
        let my_boxes: Vec<_> = mine
            .clone()
            .map(|l| self.tree.cell_box(l, bbox, curve))
            .collect();
        let remote: Vec<usize> = (0..self.tree.num_leaves())
            .filter(|l| !mine.contains(l))
            .collect();
        let remote_boxes: Vec<_> = remote
            .iter()
            .map(|&l| self.tree.cell_box(l, bbox, curve))
            .collect();
        let remote_owner: Vec<usize> = remote.iter().map(|&l| a.leaf_owner(l)).collect();
        // Cell boxes come from rounded key arithmetic: pad by a relative hair.
        let pad = 1e-9 * bbox.lengths().iter().fold(0.0f64, |m, &l| m.max(l));
        let candidates = candidate_cells(bbox, &my_boxes, &remote_boxes, radius + pad);
        let r2 = (radius + pad) * (radius + pad);
        let [x, y, z] = p.positions();
        let starts = self.tree.starts();
        // Per own leaf: (peer, particle) pairs, in particle order.
        let per_leaf: Vec<Vec<(usize, u32)>> = mine
            .clone()
            .into_par_iter()
            .zip(candidates.par_iter())
            .map(|(leaf, cands)| {
                let mut out = Vec::new();
                if cands.is_empty() {
                    return out;
                }
                let lo = self.keys.partition_point(|&k| k < starts[leaf]);
                let hi = self.keys.partition_point(|&k| k < starts[leaf + 1]);
                let mut peers: Vec<usize> = Vec::new();
                for i in lo..hi {
                    peers.clear();
                    let pos = [x[i], y[i], z[i]];
                    for &c in cands {
                        let owner = remote_owner[c as usize];
                        if !peers.contains(&owner) {
                            let (blo, bhi) = remote_boxes[c as usize];
                            if bbox.distance2_to_box(pos, blo, bhi) < r2 {
                                peers.push(owner);
                            }
                        }
                    }
                    out.extend(peers.iter().map(|&r| (r, i as u32)));
                }
                out
            })
            .collect();
        let mut plan: Vec<(usize, Vec<u32>)> = Vec::new();
        for pairs in per_leaf {
            for (r, i) in pairs {
                match plan.iter_mut().find(|(q, _)| *q == r) {
                    Some((_, v)) => v.push(i),
                    None => plan.push((r, vec![i])),
                }
            }
        }
        plan.sort_by_key(|(r, _)| *r);
        let sends = plan
            .iter()
            .map(|(r, idx)| {
                let mut buf = Vec::with_capacity(idx.len() * p.halo_words());
                p.pack_halos(idx, &mut buf);
                (*r, buf)
            })
            .collect();
        (sends, plan)
    }

    /// Puts the halos appended after the `n_owned` owned particles into
    /// curve order around them: halos with keys below `klo` first, then the
    /// owned particles, then the rest. Returns the number of leading halos
    /// and leaves in `scratch_keys[k]` the new index of the k-th halo
    /// received (old index `n_owned + k`).
    fn place_halos<P: ParticleFields>(
        &mut self,
        p: &mut P,
        bbox: &BoundingBox,
        n_owned: usize,
        klo: u64,
    ) -> usize {
        let n = p.len();
        let [x, y, z] = p.positions();
        let mut halo_keys = Vec::new();
        compute_keys(
            bbox,
            self.config.curve,
            &x[n_owned..],
            &y[n_owned..],
            &z[n_owned..],
            &mut halo_keys,
        );
        let ids = &p.ids()[n_owned..];
        let mut order: Vec<u32> = (0..(n - n_owned) as u32).collect();
        order.sort_unstable_by_key(|&a| (halo_keys[a as usize], ids[a as usize]));
        let n_low = order.partition_point(|&a| halo_keys[a as usize] < klo);
        let mut keys = Vec::with_capacity(n);
        keys.extend(order[..n_low].iter().map(|&a| halo_keys[a as usize]));
        keys.extend_from_slice(&self.keys[..n_owned]);
        keys.extend(order[n_low..].iter().map(|&a| halo_keys[a as usize]));
        self.keys = keys;
        // Only the halos move and the owned block shifts by n_low: a
        // full reorder of every field took 10 ms of rank 0's 47 ms sync
        // (Sedov 80^3, 2 ranks).
        p.place_halos(n_owned, &order, n_low, &mut self.scratch);
        // New index of each halo: its rank in `order`, past the owned
        // block for those above it.
        self.scratch_keys.clear();
        self.scratch_keys.resize(n - n_owned, 0);
        for (k, &old) in order.iter().enumerate() {
            self.scratch_keys[old as usize] = halo_slot(k, n_low, n_owned) as u64;
        }
        n_low
    }
}

/// `[-min x, -min y, -min z, max x, max y, max z, max h]` of the particles.
fn local_extent<P: ParticleFields>(p: &P) -> Result<[f64; 7], DomainError> {
    let [x, y, z] = p.positions();
    let h = p.smoothing_lengths();
    let mut e = [f64::NEG_INFINITY; 7];
    for i in 0..p.len() {
        let v = [x[i], y[i], z[i], h[i]];
        if let Some(k) = v.iter().position(|a| !a.is_finite()) {
            return Err(DomainError::NonFinite {
                id: p.ids()[i],
                what: ["x", "y", "z", "h"][k],
                value: v[k],
            });
        }
        for k in 0..3 {
            e[k] = e[k].max(-v[k]);
            e[k + 3] = e[k + 3].max(v[k]);
        }
        e[6] = e[6].max(v[3]);
    }
    Ok(e)
}

/// Every particle finite and inside the open axes of `bbox`.
fn check_inside<P: ParticleFields>(p: &P, bbox: &BoundingBox) -> Result<(), DomainError> {
    let [x, y, z] = p.positions();
    let (lo, hi) = (bbox.lo(), bbox.hi());
    for i in 0..p.len() {
        let v = [x[i], y[i], z[i]];
        for k in 0..3 {
            if !v[k].is_finite() {
                return Err(DomainError::NonFinite {
                    id: p.ids()[i],
                    what: ["x", "y", "z"][k],
                    value: v[k],
                });
            }
            if !(bbox.is_periodic(k) || (lo[k] <= v[k] && v[k] <= hi[k])) {
                return Err(DomainError::OutsideBox {
                    id: p.ids()[i],
                    axis: k,
                    value: v[k],
                    lo: lo[k],
                    hi: hi[k],
                });
            }
        }
    }
    Ok(())
}

/// Sets the open axes of `bbox` to the global extent, padded as
/// [`BoundingBox::enclosing`] pads.
fn refit(bbox: &mut BoundingBox, ext: &[f64; 7]) -> Result<(), DomainError> {
    let b = bbox.boundary();
    if b.iter().all(|&k| k == Boundary::Periodic) {
        return Ok(());
    }
    let (mut lo, mut hi) = (bbox.lo(), bbox.hi());
    for k in 0..3 {
        if b[k] == Boundary::Open {
            let (l, h) = (-ext[k], ext[k + 3]);
            let scale = (h - l).max(l.abs().max(h.abs())).max(f64::MIN_POSITIVE);
            lo[k] = l - scale * 1e-9;
            hi[k] = h + scale * 1e-9;
        }
    }
    *bbox = BoundingBox::new(lo, hi, b)?;
    Ok(())
}
