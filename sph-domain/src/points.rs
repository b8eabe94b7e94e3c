//! The smallest particle container: ids, positions and smoothing lengths.

use crate::ParticleFields;
use std::ops::Range;

/// Particles as ids, positions and smoothing lengths only: enough to
/// decompose a point set (an N-body code, a test, a benchmark).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Points {
    /// Unique ids.
    pub id: Vec<u64>,
    /// Coordinates.
    pub x: Vec<f64>,
    /// Coordinates.
    pub y: Vec<f64>,
    /// Coordinates.
    pub z: Vec<f64>,
    /// Smoothing lengths (interaction radius / 2).
    pub h: Vec<f64>,
}

impl Points {
    /// Appends a particle.
    pub fn push(&mut self, id: u64, pos: [f64; 3], h: f64) {
        self.id.push(id);
        self.x.push(pos[0]);
        self.y.push(pos[1]);
        self.z.push(pos[2]);
        self.h.push(h);
    }

    fn columns(&mut self) -> [&mut Vec<f64>; 4] {
        [&mut self.x, &mut self.y, &mut self.z, &mut self.h]
    }
}

impl ParticleFields for Points {
    fn len(&self) -> usize {
        self.id.len()
    }

    fn ids(&self) -> &[u64] {
        &self.id
    }

    fn positions(&self) -> [&[f64]; 3] {
        [&self.x, &self.y, &self.z]
    }

    fn smoothing_lengths(&self) -> &[f64] {
        &self.h
    }

    fn packed_words(&self) -> usize {
        5
    }

    fn pack(&self, i: usize, out: &mut Vec<u64>) {
        out.extend([
            self.id[i],
            self.x[i].to_bits(),
            self.y[i].to_bits(),
            self.z[i].to_bits(),
            self.h[i].to_bits(),
        ]);
    }

    fn push_packed(&mut self, w: &[u64]) {
        let f = |k: usize| f64::from_bits(w[k]);
        self.push(w[0], [f(1), f(2), f(3)], f(4));
    }

    fn keep(&mut self, r: Range<usize>) {
        self.id.truncate(r.end);
        self.id.drain(..r.start);
        for v in self.columns() {
            v.truncate(r.end);
            v.drain(..r.start);
        }
    }

    fn reorder(&mut self, perm: &[u32], scratch: &mut Vec<u64>) {
        sph_tree::apply_permutation(perm, &mut self.id, scratch);
        for v in self.columns() {
            sph_tree::apply_permutation_f64(perm, v, scratch);
        }
    }
}
