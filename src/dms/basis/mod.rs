//! The DMS basis at evaluation points (kernel `dms_basis`; SPEC §2.3, seed
//! eq. 2.6–2.10): for every point, the weights of the shared controls of
//! every triangle whose knot hull contains it, with their derivatives.
//!
//! Per point `P` the host lists the contributing triangles
//! ([`crate::dms::neighbourhood::Supports::candidates`]) and the distinct controls they name, sorted:
//! the point's *row* (`rows.row(P)`). Each candidate's six B-splines `N_β`
//! land in the row entry of their control through `slot_entry`, so one
//! invocation owns its row and sums without atomics. The output per row
//! entry is `[Σ N, Σ ∂N/∂u, Σ ∂N/∂v, 0]` in the centred parameter plane.
//!
//! f32 layout: every triangle is evaluated in its own frame, origin at its
//! first vertex (`r0`): `tri_knots` holds five `vec4` per triangle, the
//! local knots `r0 … t2` (18 floats, each `f32(k) − f32(o)` rounded once)
//! and the origin `o` in the fifth's `zw`; a point `u` becomes `f32(u) −
//! o` in the kernel, so a point that is a vertex of the triangle coincides
//! bit for bit with its knot. Orientation tests on a knot line are made
//! once per (point, triangle), in the line's canonical knot order, and
//! shared by every degree-0 triple on it, so the half-open decisions stay
//! consistent inside one triangle's recursion (docs/design/dms.md §7.2).

pub mod cpu;
pub mod gpu;

use glam::DVec2;

use super::domain::Domain;
use crate::gpu::Backend;
use crate::mesh::Csr;
use crate::{Error, Result};

/// Flat inputs of `dms_basis`.
#[derive(Debug, Clone)]
pub struct BasisInput {
    /// Evaluation points, relative to the domain centre.
    pub points: Vec<[f32; 2]>,
    /// Five per triangle (module docs).
    pub tri_knots: Vec<[f32; 4]>,
    /// Point → contributing triangles, ascending.
    pub candidates: Csr,
    /// Six per candidate (B-splines in `BETAS` order): the absolute index of
    /// the row entry its weight adds to.
    pub slot_entry: Vec<u32>,
    /// Point → distinct controls, ascending; entry `k` of the output is
    /// `rows.targets[k]`'s weight.
    pub rows: Csr,
}

/// A point's weights over controls: `weights[k]` belongs to control
/// `rows.targets[k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct BasisRows {
    pub rows: Csr,
    /// `[N, ∂N/∂u, ∂N/∂v, 0]` per row entry.
    pub weights: Vec<[f32; 4]>,
}

impl BasisInput {
    /// The inputs for the parameter points `points` of `domain`.
    ///
    /// Errors: more row entries or candidates than `u32` indexes
    /// ([`Error::Limit`]).
    pub fn new(domain: &Domain, points: &[DVec2]) -> Result<BasisInput> {
        let c = domain.centre;
        let f = |p: DVec2| [(p.x - c.x) as f32, (p.y - c.y) as f32];
        let tri_knots: Vec<[f32; 4]> = (0..domain.triangles.len() as u32)
            .flat_map(|t| {
                let k = domain.triangle_knots(t).map(f);
                let o = k[0];
                let l = k.map(|p| [p[0] - o[0], p[1] - o[1]]);
                [
                    [l[0][0], l[0][1], l[1][0], l[1][1]],
                    [l[2][0], l[2][1], l[3][0], l[3][1]],
                    [l[4][0], l[4][1], l[5][0], l[5][1]],
                    [l[6][0], l[6][1], l[7][0], l[7][1]],
                    [l[8][0], l[8][1], o[0], o[1]],
                ]
            })
            .collect();
        let candidates = domain.supports.candidates(points);
        let n_slots = 6 * candidates.targets.len() as u64;
        if n_slots > u64::from(u32::MAX) {
            return Err(Error::limit("dms_basis: B-spline slots", n_slots, u32::MAX));
        }
        // Per point (in parallel): its distinct controls and, per slot, the
        // position of the slot's control among them.
        use rayon::prelude::*;
        let per_point: Vec<(Vec<u32>, Vec<u32>)> = (0..points.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|p| {
                let tris = candidates.row(p);
                let slots: Vec<u32> = (tris.iter())
                    .flat_map(|&t| (0..6).map(move |b| domain.control(t, b)))
                    .collect();
                let mut row = slots.clone();
                row.sort_unstable();
                row.dedup();
                let local = (slots.iter())
                    .map(|c| row.binary_search(c).unwrap_or(0) as u32)
                    .collect();
                (row, local)
            })
            .collect();
        let total: u64 = per_point.iter().map(|(r, _)| r.len() as u64).sum();
        if total > u64::from(u32::MAX) {
            return Err(Error::limit("dms_basis: row entries", total, u32::MAX));
        }
        let mut slot_entry: Vec<u32> = Vec::with_capacity(n_slots as usize);
        let mut offsets: Vec<u32> = Vec::with_capacity(points.len() + 1);
        let mut targets: Vec<u32> = Vec::with_capacity(total as usize);
        offsets.push(0);
        for (row, local) in &per_point {
            let base = targets.len() as u32;
            slot_entry.extend(local.iter().map(|k| base + k));
            targets.extend_from_slice(row);
            offsets.push(targets.len() as u32);
        }
        let rows = Csr { offsets, targets };
        Ok(BasisInput {
            points: points.iter().map(|&p| f(p)).collect(),
            tri_knots,
            candidates,
            slot_entry,
            rows,
        })
    }
}

impl BasisInput {
    /// The inputs of the points `range` alone (offsets and entries
    /// rebased), for dispatches that fit one storage binding each.
    pub fn part(&self, range: std::ops::Range<usize>) -> BasisInput {
        let c0 = self.candidates.offsets[range.start];
        let c1 = self.candidates.offsets[range.end];
        let r0 = self.rows.offsets[range.start];
        BasisInput {
            points: self.points[range.clone()].to_vec(),
            tri_knots: self.tri_knots.clone(),
            candidates: self.candidates.slice(range.clone()),
            slot_entry: self.slot_entry[6 * c0 as usize..6 * c1 as usize]
                .iter()
                .map(|e| e - r0)
                .collect(),
            rows: self.rows.slice(range),
        }
    }
}

/// The basis rows of `points` over `domain`'s controls on `backend`.
pub fn dms_basis(domain: &Domain, points: &[DVec2], backend: Backend<'_>) -> Result<BasisRows> {
    let input = BasisInput::new(domain, points)?;
    let weights = match backend {
        Backend::Cpu => cpu::dms_basis(&input),
        Backend::Gpu(g) => gpu::dms_basis(g, &input)?,
    };
    Ok(BasisRows {
        rows: input.rows,
        weights,
    })
}
