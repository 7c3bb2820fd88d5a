//! The kernels' gather adjacency (CSR of packed neighbour/material entries)
//! built from a network's springs, and the queries a built network answers
//! (material table, node counts, nodal stiffness, traffic per iteration).

use glam::Vec3;
use rayon::prelude::*;

use super::{MAX_MATERIALS, Material, Spring, SpringNetwork};

const INDEX_MASK: u32 = (1 << 28) - 1;

/// The kernels' gather adjacency: row `i` (a free node) lists one entry per
/// spring at `i`, sorted by neighbour id. An entry is `j | material << 28`;
/// the rest length is not stored: the kernels take l_ij = |x_rest,i −
/// x_rest,j| from the rest positions they gather anyway (rest length =
/// initial length), in f32 with the very difference that starts r_ij, so a
/// spring at rest has extension exactly 0.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SpringCsr {
    /// #free + 1 row starts.
    pub offsets: Vec<u32>,
    /// Packed entries (4 bytes each).
    pub entries: Vec<u32>,
}

impl SpringCsr {
    /// Unpacks an entry into `(neighbour, material)`.
    #[inline(always)]
    pub fn unpack(e: u32) -> (usize, usize) {
        ((e & INDEX_MASK) as usize, (e >> 28) as usize)
    }
}

impl SpringNetwork {
    pub(super) fn gather_csr(&self) -> SpringCsr {
        let nf = self.n_free as u32;
        let entry = |j: u32, s: &Spring| j | (u32::from(s.material) << 28);
        // Springs are sorted by (a, b): row i receives its (x, i) springs in
        // increasing x before its (i, y) springs in increasing y, so every
        // row comes out sorted by neighbour id.
        let pairs: Vec<(u32, u32)> = self
            .springs
            .iter()
            .flat_map(|s| {
                let ab = (s.a < nf).then(|| (s.a, entry(s.b, s)));
                let ba = (s.b < nf).then(|| (s.b, entry(s.a, s)));
                ab.into_iter().chain(ba)
            })
            .collect();
        let mut counts = vec![0u32; self.n_free + 1];
        for &(r, _) in &pairs {
            counts[r as usize + 1] += 1;
        }
        for i in 0..self.n_free {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut entries = vec![0u32; pairs.len()];
        for (r, e) in pairs {
            let slot = &mut counts[r as usize];
            entries[*slot as usize] = e;
            *slot += 1;
        }
        SpringCsr { offsets, entries }
    }

    /// The kernels' material table: row m is material m's
    /// [`Material::table_row`], unused rows zero.
    pub fn material_table(&self) -> [[f32; 4]; MAX_MATERIALS] {
        let mut table = [[0.0f32; 4]; MAX_MATERIALS];
        for (row, m) in table.iter_mut().zip(&self.materials) {
            *row = m.table_row();
        }
        table
    }

    /// Total number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.rest.len()
    }

    /// Number of fixed (bone) nodes.
    pub fn n_bone(&self) -> usize {
        self.rest.len() - self.n_free
    }

    /// Rest positions of the bone layer (bone vertex ids `0..n_bone`).
    pub fn bone_rest(&self) -> &[[f32; 4]] {
        &self.rest[self.n_free..]
    }

    /// Spring count per class, in [`SpringClass::ALL`](super::SpringClass::ALL) order.
    pub fn class_counts(&self) -> [usize; 6] {
        let mut c = [0; 6];
        for s in &self.springs {
            c[s.class.index()] += 1;
        }
        c
    }

    /// Σ_j c_max,ij over the springs of each free node (the largest nodal
    /// stiffness).
    pub fn nodal_stiffness(&self) -> Vec<f32> {
        let cmax: Vec<f32> = self.materials.iter().map(Material::c_max).collect();
        (0..self.n_free)
            .into_par_iter()
            .map(|i| {
                let (s, e) = (
                    self.csr.offsets[i] as usize,
                    self.csr.offsets[i + 1] as usize,
                );
                self.csr.entries[s..e]
                    .iter()
                    .map(|&en| cmax[SpringCsr::unpack(en).1] as f64)
                    .sum::<f64>() as f32
            })
            .collect()
    }

    /// Length of the rest bounding-box diagonal (scale for default thresholds).
    pub fn diagonal(&self) -> f32 {
        let (lo, hi) = self.rest.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let v = Vec3::new(p[0], p[1], p[2]);
                (lo.min(v), hi.max(v))
            },
        );
        (hi - lo).length()
    }

    /// The bytes one iteration of the step kernels must move at least:
    /// per free node the row offset (4), own rest position, displacement
    /// and velocity read (48), displacement and velocity written (32); per
    /// CSR entry 4 bytes; the fixed nodes' rest positions and displacements
    /// (32) read once. Other neighbour reads are assumed cached (compulsory
    /// traffic only).
    pub fn bytes_per_iteration(&self) -> u64 {
        self.n_free as u64 * (4 + 48 + 32)
            + self.n_bone() as u64 * 32
            + self.csr.entries.len() as u64 * 4
    }
}
