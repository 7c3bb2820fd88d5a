//! The skeletal field as flat rows for the kernel `implicit_field` and its
//! mirror, with a grid that culls primitives too weak to matter.
//!
//! Rows (`skeleton`, `[f32; 4]` each), primitive i at rows 2i and 2i + 1:
//!
//! ```text
//!   (p0, p1, w, 1/R²)  (dp0/dt, dp1/dt, dw/dt, 0)      p = (a, b) blobby, (R, strength) otherwise
//! ```
//!
//! then, from `piece_base`, four rows per segment of a skeleton (a point is
//! one segment with a = b):
//!
//! ```text
//!   (a, 1/|b − a|² or 0)  (b, 0)  (da/dt, 0)  (db/dt, 0)
//! ```
//!
//! `table` (`u32`): the influence kind of every primitive, the end of each
//! primitive's pieces, then the cull grid's cell starts (absolute indices
//! into `table`, #cells + 1) and the ascending primitive ids per cell.
//!
//! **Culling.** With n primitives, τ = ε_f32·I/(2n): a primitive whose
//! |w·e| stays below τ beyond radius r_s (blobby: r_s = √(ln(|w b|/τ)/a);
//! Wyvill, metaball: their radius) is listed only in the cells that its
//! support (the points within r_s of a skeleton piece) reaches, so the
//! dropped sum stays below half an ulp of I. A point
//! outside the grid has F = 0. Both backends sum a cell's primitives in
//! ascending id.

pub mod cpu;
pub mod gpu;

use glam::{DVec3, UVec3, Vec3};

use super::{Blend, Influence, Pose};
use crate::gpu::Backend;
use crate::{Error, Result};

/// Uniform parameters of the skeletal field (`kernels/shared/skeletal_field.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, encase::ShaderType)]
pub struct FieldParams {
    /// World position of the cull grid's corner.
    pub grid_origin: Vec3,
    /// 1 / cell edge.
    pub inv_cell: f32,
    /// Cells per axis.
    pub grid_dims: UVec3,
    /// Number of primitives.
    pub n_prims: u32,
    /// The iso value I (outputs carry F − I).
    pub iso: f32,
    /// 1 for [`Blend::Max`], 0 for the sums.
    pub blend_max: u32,
    /// First piece row in `skeleton`.
    pub piece_base: u32,
    /// Index in `table` of the first cell start.
    pub cell_base: u32,
}

/// The flat field of one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldInput {
    pub params: FieldParams,
    pub skeleton: Vec<[f32; 4]>,
    pub table: Vec<u32>,
}

/// F − I, ∇F and F_t at one point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// F(x) − I (positive inside).
    pub value: f32,
    pub grad: [f32; 3],
    /// ∂F/∂t at fixed x.
    pub rate: f32,
}

/// Most cull cells.
const MAX_CELLS: usize = 1 << 21;
/// Most (cell, primitive) entries of the cull grid.
const MAX_ENTRIES: usize = 1 << 26;

/// The squared distance of `x` below which `influence` (times `w`) may
/// exceed `floor` in magnitude: `None` when it never does.
pub(crate) fn reach(influence: &Influence, w: f64, floor: f64) -> Option<f64> {
    let m = (w * influence.strength()).abs();
    if m <= floor {
        return None;
    }
    Some(match *influence {
        Influence::Blobby { a, .. } => (m / floor).ln() / a,
        Influence::Wyvill { radius, .. } | Influence::Metaball { radius, .. } => radius * radius,
    })
}

/// f32 rows of a vector and a last component.
fn row(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

impl FieldInput {
    /// Flattens `pose` and builds its cull grid.
    ///
    /// Errors: more primitives, pieces or cull entries than the kernel
    /// numbers ([`Error::Limit`]).
    pub fn new(pose: &Pose) -> Result<FieldInput> {
        let n = pose.primitives.len();
        let n_prims = u32::try_from(n)
            .map_err(|_| Error::limit("implicit_field: primitives", n, u32::MAX))?;
        let tau = f64::from(f32::EPSILON) * pose.iso / (2.0 * n.max(1) as f64);
        let mut skeleton = Vec::with_capacity(2 * n);
        let mut kinds = Vec::with_capacity(n);
        let mut piece_ends = Vec::with_capacity(n);
        let mut pieces: Vec<[f32; 4]> = Vec::new();
        // Support capsules per piece.
        let mut supports: Vec<Support> = Vec::new();
        for (i, (p, r)) in pose.primitives.iter().zip(&pose.rates).enumerate() {
            let [p0, p1] = p.influence.params();
            let inv_r2 = match p.influence {
                Influence::Blobby { .. } => 0.0,
                _ => 1.0 / (p0 * p0),
            };
            skeleton.push(row(DVec3::new(p0, p1, p.weight), inv_r2));
            skeleton.push(row(DVec3::new(r.params[0], r.params[1], r.weight), 0.0));
            kinds.push(p.influence.code());
            let pts = p.skeleton.points();
            let reach2 = reach(&p.influence, p.weight, tau);
            for [ia, ib] in p.skeleton.pieces() {
                let (a, b) = (pts[ia], pts[ib]);
                let l2 = (b - a).length_squared();
                pieces.push(row(a, if l2 > 0.0 { 1.0 / l2 } else { 0.0 }));
                pieces.push(row(b, 0.0));
                pieces.push(row(r.points[ia], 0.0));
                pieces.push(row(r.points[ib], 0.0));
                if let Some(s2) = reach2 {
                    supports.push(Support {
                        prim: i as u32,
                        a,
                        b,
                        radius: s2.sqrt(),
                    });
                }
            }
            piece_ends.push(
                u32::try_from(pieces.len() / 4).map_err(|_| {
                    Error::limit("implicit_field: pieces", pieces.len() / 4, u32::MAX)
                })?,
            );
        }
        let piece_base = skeleton.len() as u32;
        skeleton.extend(pieces);
        let (grid_origin, inv_cell, dims, cells) = cull_grid(&supports)?;
        let mut table = kinds;
        table.extend(piece_ends);
        let cell_base = table.len() as u32;
        let ids_base = cell_base as usize + cells.len() + 1;
        let mut start = ids_base;
        let mut ids: Vec<u32> = Vec::new();
        for list in &cells {
            table.push(
                u32::try_from(start)
                    .map_err(|_| Error::limit("implicit_field: table", start, u32::MAX))?,
            );
            start += list.len();
            ids.extend(list);
        }
        table.push(
            u32::try_from(start)
                .map_err(|_| Error::limit("implicit_field: table", start, u32::MAX))?,
        );
        table.extend(ids);
        Ok(FieldInput {
            params: FieldParams {
                grid_origin,
                inv_cell,
                grid_dims: dims,
                n_prims,
                iso: pose.iso as f32,
                blend_max: u32::from(pose.blend == Blend::Max),
                piece_base,
                cell_base,
            },
            skeleton,
            table,
        })
    }

    /// Number of cull cells.
    pub fn n_cells(&self) -> usize {
        let d = self.params.grid_dims;
        (d.x * d.y * d.z) as usize
    }

    /// Mean number of primitives listed per cull cell.
    pub fn mean_cell_primitives(&self) -> f64 {
        let c = self.params.cell_base as usize;
        let n = self.n_cells();
        f64::from(self.table[c + n] - self.table[c]) / n as f64
    }
}

/// Where one skeleton piece of a primitive may matter: the points within
/// `radius` of the segment `a`–`b`.
struct Support {
    prim: u32,
    a: DVec3,
    b: DVec3,
    radius: f64,
}

impl Support {
    /// Distance from `x` to the segment.
    fn distance(&self, x: DVec3) -> f64 {
        let ab = self.b - self.a;
        let l2 = ab.length_squared();
        let u = if l2 > 0.0 {
            ((x - self.a).dot(ab) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x - (self.a + u * ab)).length()
    }
}

/// A uniform grid over the supports, with the ascending ids of the
/// primitives whose support capsules may reach into each cell: (origin,
/// 1/cell, dims, lists).
///
/// Cells are a quarter of the median support radius, at most `MAX_CELLS`.
/// A cell lists a primitive when one of its capsules comes within half a
/// cell diagonal (plus a hundredth of a cell, for f32 lookups near a face)
/// of the cell's centre: every cell a capsule touches, and fewer than its
/// bounding box would give (a sphere fills half its box).
fn cull_grid(supports: &[Support]) -> Result<(Vec3, f32, UVec3, Vec<Vec<u32>>)> {
    if supports.is_empty() {
        return Ok((Vec3::ZERO, 1.0, UVec3::ONE, vec![Vec::new()]));
    }
    let lo = supports.iter().fold(DVec3::INFINITY, |m, s| {
        m.min(s.a.min(s.b) - DVec3::splat(s.radius))
    });
    let hi = supports.iter().fold(DVec3::NEG_INFINITY, |m, s| {
        m.max(s.a.max(s.b) + DVec3::splat(s.radius))
    });
    let extent = (hi - lo).max(DVec3::splat(1e-9));
    let mut radii: Vec<f64> = supports.iter().map(|s| s.radius).collect();
    radii.sort_by(f64::total_cmp);
    let mut cell = (radii[radii.len() / 2] / 4.0).max(extent.max_element() / 256.0);
    let count = |c: f64| (extent / c).ceil().max(DVec3::ONE);
    while count(cell).element_product() > MAX_CELLS as f64 {
        cell *= 1.25;
    }
    // The origin and 1/cell the kernel sees, in f32.
    let origin = lo.as_vec3();
    let inv_cell = (1.0 / cell) as f32;
    let step = 1.0 / f64::from(inv_cell);
    let dims = count(cell).as_uvec3();
    let n_cells = (dims.x * dims.y * dims.z) as usize;
    let mut cells = vec![Vec::new(); n_cells];
    let mut entries = 0usize;
    let slack = step * (0.5 * 3f64.sqrt() + 0.01);
    let to_cell = |p: DVec3| {
        ((p - origin.as_dvec3()) / step)
            .floor()
            .clamp(DVec3::ZERO, (dims - 1).as_dvec3())
            .as_uvec3()
    };
    for s in supports {
        let r = DVec3::splat(s.radius + slack);
        let (c0, c1) = (to_cell(s.a.min(s.b) - r), to_cell(s.a.max(s.b) + r));
        for z in c0.z..=c1.z {
            for y in c0.y..=c1.y {
                for x in c0.x..=c1.x {
                    let centre = origin.as_dvec3() + (UVec3::new(x, y, z).as_dvec3() + 0.5) * step;
                    if s.distance(centre) > s.radius + slack {
                        continue;
                    }
                    let list: &mut Vec<u32> = &mut cells[(x + dims.x * (y + dims.y * z)) as usize];
                    if list.last() != Some(&s.prim) {
                        list.push(s.prim);
                        entries += 1;
                    }
                }
            }
        }
        if entries > MAX_ENTRIES {
            return Err(Error::limit(
                "implicit_field: cull grid entries",
                entries,
                MAX_ENTRIES,
            ));
        }
    }
    Ok((origin, inv_cell, dims, cells))
}

/// F − I, ∇F and F_t at `points` on `backend`.
pub fn implicit_field(
    input: &FieldInput,
    points: &[[f32; 4]],
    backend: Backend<'_>,
) -> Result<Vec<Sample>> {
    match backend {
        Backend::Cpu => Ok(cpu::implicit_field(input, points)),
        Backend::Gpu(g) => gpu::implicit_field(g, input, points),
    }
}
