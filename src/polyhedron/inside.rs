//! Point-in-polyhedron for the non-convex merged surface (seed 003 §4.4.3)
//! by exact ray parity.
//!
//! The seed casts a half-line from the cell `c` parallel to a coordinate
//! axis, projects every face to the perpendicular coordinate plane, tests
//! the foot point against the projected face with a second half-line and
//! counts the faces hit beyond `c`: odd is inside. Here the faces are the
//! exact triangles of [`MergedSurface::triangles`] (faces may be
//! non-convex and have holes, where the seed too needs the projection
//! method), and the degenerate cases are decided by a symbolic
//! perturbation of the foot point, `(x + ε, y + ε²)`: it lies on no
//! projected edge, so a ray through an edge or a vertex counts each sheet
//! of the surface exactly once, and faces parallel to the ray (projecting
//! to segments) are never hit. A point on a closed triangle is reported
//! [`Side::On`] separately (the seed counts it as inside; callers apply
//! the stored labels).
//!
//! **Relation to [`Polyhedron::voxelize`].** The merged surface bounds the
//! region `Σ sign·χ(H)` of the 3-D shells. Voxels whose centre is not on
//! the surface and not in a lower-dimensional shell (points, segments and
//! flat polygons carry no volume; they are the stored labels of §3.4,
//! §7.2) are held exactly when the ray parity says inside; the others are
//! resolved by the shell tree (closed shell, no child's region). With that
//! resolution [`Polyhedron::voxelize_ray_parity`] equals
//! [`Polyhedron::voxelize`] voxel for voxel on every object tested (seed
//! cylinders, torus, dented ellipsoid, cavity with island, random
//! carvings, CT bone).
//!
//! All arithmetic is exact integer arithmetic on combinatorial coordinates
//! (i128 for products), within ±2^24 ([`MAX_COORD`]).

use crate::foundation::exact::{P2, cross_wide, orient2, sub};
use crate::gpu::Backend;
use crate::hull_scan::{RowSpans, Side, VoxelBox};
use crate::voxel::DigitalObject;

use super::polyhedrize::{differences, verify_box, voxel_at};
use super::{MergedSurface, Polyhedron, ShellGeometry};

/// Largest combinatorial coordinate magnitude (surface vertices and voxel
/// centres of the box) for which the degree-3 products stay far inside
/// i128.
pub const MAX_COORD: i64 = 1 << 24;

/// The normal `(b − a) × (c − a)` of triangle `a b c`, in `i128`.
fn cross3(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> [i128; 3] {
    cross_wide(sub(b, a), sub(c, a))
}

/// Whether the foot point `f + (ε, ε²)` lies strictly inside the
/// counter-clockwise triangle `t` (never on an edge).
fn contains_perturbed(t: [P2; 3], f: P2) -> bool {
    (0..3).all(|k| {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let o = orient2(p, q, f);
        // orient2(p, q, f + δ) = o + d_x·ε² − d_y·ε for d = q − p.
        let s = if o != 0 {
            o
        } else if q[1] != p[1] {
            i128::from(p[1] - q[1])
        } else {
            i128::from(q[0] - p[0])
        };
        s > 0
    })
}

/// The local indices `i ∈ [0, n)` whose lattice coordinate `u0 + 2i` lies
/// in the closed counter-clockwise triangle `t` (points `(u, v)`) on the
/// line `v`, as an inclusive range; `None` when there are none.
fn span(t: [P2; 3], v: i64, u0: i64, n: usize) -> Option<(usize, usize)> {
    let (mut lo, mut hi) = (0i128, n as i128 - 1);
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let (du, dv) = (i128::from(q[0] - p[0]), i128::from(q[1] - p[1]));
        // orient2(p, q, (u0 + 2i, v)) ≥ 0  ⇔  2·dv·i ≤ r.
        let r = du * i128::from(v - p[1]) - dv * i128::from(u0 - p[0]);
        match dv.signum() {
            1 => hi = hi.min(r.div_euclid(2 * dv)),
            -1 => lo = lo.max(ceil_div(r, 2 * dv)),
            _ if r < 0 => return None,
            _ => {}
        }
    }
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// `⌈a / b⌉` for `b ≠ 0`.
fn ceil_div(a: i128, b: i128) -> i128 {
    let (a, b) = if b < 0 { (-a, -b) } else { (a, b) };
    -((-a).div_euclid(b))
}

/// `p` with the coordinates cyclically shifted so that `axis` comes last
/// (keeps handedness).
fn to_axis(p: [i64; 3], axis: usize) -> [i64; 3] {
    [p[(axis + 1) % 3], p[(axis + 2) % 3], p[axis]]
}

/// Whether `c` lies in the closed triangle `t` (exact, any orientation).
fn on_triangle(t: [[i64; 3]; 3], c: [i64; 3]) -> bool {
    let n = cross3(t[0], t[1], t[2]);
    let d: [i128; 3] = std::array::from_fn(|k| i128::from(c[k] - t[0][k]));
    if n[0] * d[0] + n[1] * d[1] + n[2] * d[2] != 0 {
        return false;
    }
    // Drop the dominant axis of the normal: the projection keeps the area.
    let k = (0..3).max_by_key(|&a| n[a].abs()).unwrap_or(2);
    let q = |p: [i64; 3]| to_axis(p, k);
    let (a, b, e, x) = (q(t[0]), q(t[1]), q(t[2]), q(c));
    let o = [
        orient2([a[0], a[1]], [b[0], b[1]], [x[0], x[1]]).signum(),
        orient2([b[0], b[1]], [e[0], e[1]], [x[0], x[1]]).signum(),
        orient2([e[0], e[1]], [a[0], a[1]], [x[0], x[1]]).signum(),
    ];
    !(o.contains(&1) && o.contains(&-1))
}

impl MergedSurface {
    /// Refuses coordinates beyond ±[`MAX_COORD`] (surface vertices or the
    /// voxel centres of `bbox`).
    fn check_coords(&self, bbox: &VoxelBox) -> crate::Result<()> {
        let box_ok = (0..3).all(|a| {
            let lo = 2 * i128::from(bbox.origin[a]) + 1;
            let hi = lo + 2 * bbox.dims[a] as i128;
            lo.abs() <= i128::from(MAX_COORD) && hi.abs() <= i128::from(MAX_COORD)
        });
        let vertices_ok = self.vertices.iter().flatten().all(|c| c.abs() <= MAX_COORD);
        if box_ok && vertices_ok {
            Ok(())
        } else {
            Err(crate::Error::param(
                "ray parity: box",
                format!("origin {:?}, {:?} voxels", bbox.origin, bbox.dims),
                format!("box and shell coordinates must lie within ±{MAX_COORD}"),
            ))
        }
    }

    /// Where every voxel centre of `bbox` lies relative to the surface
    /// (§4.4.3): one [`Side`] per voxel, x fastest. A ray parallel to +z
    /// per voxel column: each triangle is rasterised over the columns its
    /// xy projection covers (exact scanline spans), its crossing height
    /// recorded as a toggle at the first voxel below it, and one sweep
    /// down the column turns toggles into parity — O(voxels + Σ columns
    /// covered per triangle), not O(voxels × triangles). Triangles
    /// parallel to z only mark the centres lying on them.
    ///
    /// Errors: the box overflows; coordinates beyond ±[`MAX_COORD`].
    pub fn classify(&self, bbox: &VoxelBox) -> crate::Result<Vec<Side>> {
        let n = bbox.n_voxels()?;
        self.check_coords(bbox)?;
        if n == 0 {
            return Ok(Vec::new());
        }
        // Bit 0: the crossing toggle (flips this voxel and all below it);
        // bit 1: the centre lies on the surface.
        let mut marks = vec![0u8; n];
        for t in &self.triangles {
            let p = t.map(|v| self.vertices[v as usize]);
            mark_triangle(p, bbox, &mut marks);
        }
        let [nx, ny, nz] = bbox.dims;
        let mut out = vec![Side::Outside; n];
        for col in 0..nx * ny {
            let mut inside = false;
            for k in (0..nz).rev() {
                let ix = col + nx * ny * k;
                inside ^= marks[ix] & 1 != 0;
                out[ix] = if marks[ix] & 2 != 0 {
                    Side::On
                } else if inside {
                    Side::Inside
                } else {
                    Side::Outside
                };
            }
        }
        Ok(out)
    }

    /// Where the point `c` (combinatorial coordinates) lies, by a ray
    /// parallel to `+axis` (0, 1 or 2) tested against every triangle:
    /// O(triangles), the single-point form of [`MergedSurface::classify`],
    /// written independently of it (perturbation `(ε², ε)` of the foot
    /// point in the two other coordinates, taken cyclically).
    ///
    /// Errors: `axis > 2`; coordinates beyond ±[`MAX_COORD`].
    pub fn side_of(&self, c: [i64; 3], axis: usize) -> crate::Result<Side> {
        if axis > 2 {
            return Err(crate::Error::param(
                "ray parity: axis",
                axis,
                "must be 0, 1 or 2",
            ));
        }
        if c.iter().any(|x| x.abs() > MAX_COORD)
            || self.vertices.iter().flatten().any(|x| x.abs() > MAX_COORD)
        {
            return Err(crate::Error::param(
                "ray parity: point",
                format!("{c:?}"),
                format!("point and shell coordinates must lie within ±{MAX_COORD}"),
            ));
        }
        let cc = to_axis(c, axis);
        let mut hits = 0usize;
        for t in &self.triangles {
            let p = t.map(|v| self.vertices[v as usize]);
            if on_triangle(p, c) {
                return Ok(Side::On);
            }
            let q = p.map(|v| to_axis(v, axis));
            let n = cross3(q[0], q[1], q[2]);
            if n[2] == 0 {
                continue;
            }
            // Foot point f + (ε², ε): strictly inside the projection?
            let inside = (0..3).all(|k| {
                let (a, b) = (q[k], q[(k + 1) % 3]);
                let o = orient2([a[0], a[1]], [b[0], b[1]], [cc[0], cc[1]]);
                let (dx, dy) = (i128::from(b[0] - a[0]), i128::from(b[1] - a[1]));
                // o + dx·ε − dy·ε², signed by the triangle's orientation.
                let s = if o != 0 {
                    o
                } else if dx != 0 {
                    dx
                } else {
                    -dy
                };
                s.signum() == n[2].signum()
            });
            if !inside {
                continue;
            }
            // Crossing beyond c: n·(x − q0) = 0 at x = (cc0, cc1, h), h > cc2.
            let d: [i128; 3] = std::array::from_fn(|k| i128::from(cc[k] - q[0][k]));
            let at_c = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            // h − cc2 = −at_c / n2.
            if (-at_c).signum() * n[2].signum() > 0 {
                hits += 1;
            }
        }
        Ok(if hits % 2 == 1 {
            Side::Inside
        } else {
            Side::Outside
        })
    }
}

/// Records triangle `p` in the column marks of `bbox` (see
/// [`MergedSurface::classify`]).
fn mark_triangle(p: [[i64; 3]; 3], bbox: &VoxelBox, marks: &mut [u8]) {
    let [nx, ny, nz] = bbox.dims;
    let base: [i64; 3] = std::array::from_fn(|a| 2 * bbox.origin[a] + 1);
    let xy = p.map(|v| [v[0], v[1]]);
    let normal = cross3(p[0], p[1], p[2]);
    if normal[2] == 0 {
        mark_vertical(p, bbox, marks);
        return;
    }
    let ccw = if normal[2] > 0 {
        xy
    } else {
        [xy[0], xy[2], xy[1]]
    };
    let (ylo, yhi) = (
        xy.iter().map(|q| q[1]).min().unwrap_or(0),
        xy.iter().map(|q| q[1]).max().unwrap_or(0),
    );
    let j_lo = ceil_div(i128::from(ylo - base[1]), 2).max(0);
    let j_hi = i128::from(yhi - base[1]).div_euclid(2).min(ny as i128 - 1);
    // Normalised so that the height of the plane over (x, y) is
    // num(x, y) / den with den > 0.
    let (sign, den) = (normal[2].signum(), normal[2].abs());
    let a: [i128; 3] = p[0].map(i128::from);
    for j in j_lo..=j_hi {
        let y = base[1] + 2 * j as i64;
        let Some((i_lo, i_hi)) = span(ccw, y, base[0], nx) else {
            continue;
        };
        for i in i_lo..=i_hi {
            let x = base[0] + 2 * i as i64;
            let num = sign
                * (normal[2] * a[2]
                    - normal[0] * (i128::from(x) - a[0])
                    - normal[1] * (i128::from(y) - a[1]));
            let col = i + nx * j as usize;
            // The centre at this height lies on the closed triangle.
            if num % den == 0 {
                let k = num / den - i128::from(base[2]);
                if k >= 0 && k % 2 == 0 && k / 2 < nz as i128 {
                    marks[col + nx * ny * (k / 2) as usize] |= 2;
                }
            }
            if contains_perturbed(ccw, [x, y]) {
                // Voxels k with base_z + 2k below the crossing: k < t.
                let t = ceil_div(num - i128::from(base[2]) * den, 2 * den).clamp(0, nz as i128);
                if t > 0 {
                    marks[col + nx * ny * (t as usize - 1)] ^= 1;
                }
            }
        }
    }
}

/// Marks the voxel centres lying on a triangle parallel to z (its xy
/// projection a segment): per lattice column on the segment, the span of
/// the triangle in z, from the triangle in (z, s) coordinates with `s` the
/// segment's dominant axis.
fn mark_vertical(p: [[i64; 3]; 3], bbox: &VoxelBox, marks: &mut [u8]) {
    let [nx, ny, nz] = bbox.dims;
    let base: [i64; 3] = std::array::from_fn(|a| 2 * bbox.origin[a] + 1);
    let span_of = |a: usize| {
        let lo = p.iter().map(|v| v[a]).min().unwrap_or(0);
        let hi = p.iter().map(|v| v[a]).max().unwrap_or(0);
        (lo, hi)
    };
    let (x_range, y_range) = (span_of(0), span_of(1));
    // s: the axis along the segment with the larger extent; w: the other.
    let (s, w) = if x_range.1 - x_range.0 >= y_range.1 - y_range.0 {
        (0, 1)
    } else {
        (1, 0)
    };
    let (lo_s, hi_s) = if s == 0 { x_range } else { y_range };
    if lo_s == hi_s {
        return;
    }
    // The segment's ends: the points of smallest and largest s.
    let ends = |pick_max: bool| {
        p.iter()
            .copied()
            .reduce(|m, v| if (v[s] > m[s]) == pick_max { v } else { m })
            .unwrap_or(p[0])
    };
    let (e0, e1) = (ends(false), ends(true));
    let zs = p.map(|v| [v[2], v[s]]);
    let zs = if orient2(zs[0], zs[1], zs[2]) > 0 {
        zs
    } else {
        [zs[0], zs[2], zs[1]]
    };
    let dims_s = if s == 0 { nx } else { ny };
    let dims_w = if w == 0 { nx } else { ny };
    let l_lo = ceil_div(i128::from(lo_s - base[s]), 2).max(0);
    let l_hi = i128::from(hi_s - base[s])
        .div_euclid(2)
        .min(dims_s as i128 - 1);
    for l in l_lo..=l_hi {
        let cs = base[s] + 2 * l as i64;
        // cw on the segment: e0 + (cs − e0_s)/(e1_s − e0_s)·(e1 − e0).
        let num = i128::from(e0[w]) * i128::from(e1[s] - e0[s])
            + i128::from(cs - e0[s]) * i128::from(e1[w] - e0[w]);
        let den = i128::from(e1[s] - e0[s]);
        if num % den != 0 {
            continue;
        }
        let m = num / den - i128::from(base[w]);
        if m < 0 || m % 2 != 0 || m / 2 >= dims_w as i128 {
            continue;
        }
        let Some((k_lo, k_hi)) = span(zs, cs, base[2], nz) else {
            continue;
        };
        let (i, j) = if s == 0 {
            (l as usize, (m / 2) as usize)
        } else {
            ((m / 2) as usize, l as usize)
        };
        for k in k_lo..=k_hi {
            marks[i + nx * (j + ny * k)] |= 2;
        }
    }
}

/// The closed-shell test of one shell, for the per-voxel tree walk:
/// points and segments directly, polytopes by the per-row spans of the
/// hull scan (the same closed test [`ShellGeometry::closed_voxels`] uses).
enum ClosedShell {
    Point([i64; 3]),
    Segment([i64; 3], [i64; 3]),
    Polytope(RowSpans),
}

impl ClosedShell {
    fn of(g: &ShellGeometry, backend: Backend<'_>) -> crate::Result<ClosedShell> {
        Ok(match g {
            ShellGeometry::Point(p) => ClosedShell::Point(*p),
            ShellGeometry::Segment(a, b) => ClosedShell::Segment(*a, *b),
            ShellGeometry::Polytope(h) => {
                let (lo, hi) = h.voxel_bbox();
                let bbox = VoxelBox {
                    origin: lo,
                    dims: std::array::from_fn(|k| (hi[k] - lo[k] + 1).max(0) as usize),
                };
                ClosedShell::Polytope(h.row_spans(&bbox, backend)?)
            }
        })
    }

    /// Voxel index bounds (inclusive; empty when some `lo > hi`) of the
    /// voxels whose centres the closed shell may hold.
    fn voxel_bounds(&self) -> ([i64; 3], [i64; 3]) {
        let voxel = |c: i64| (c - 1).div_euclid(2);
        match self {
            ClosedShell::Point(p) => (p.map(voxel), p.map(voxel)),
            ClosedShell::Segment(a, b) => (
                std::array::from_fn(|k| voxel(a[k].min(b[k]))),
                std::array::from_fn(|k| voxel(a[k].max(b[k]))),
            ),
            ClosedShell::Polytope(r) => (
                r.bbox.origin,
                std::array::from_fn(|k| r.bbox.origin[k] + r.bbox.dims[k] as i64 - 1),
            ),
        }
    }

    /// Whether the closed shell holds the centre of voxel `v`.
    fn contains(&self, v: [i64; 3]) -> bool {
        let c = v.map(|x| 2 * x + 1);
        match self {
            ClosedShell::Point(p) => *p == c,
            ClosedShell::Segment(a, b) => {
                let d: [i128; 3] = std::array::from_fn(|k| i128::from(b[k] - a[k]));
                let e: [i128; 3] = std::array::from_fn(|k| i128::from(c[k] - a[k]));
                let dot = |u: [i128; 3], v: [i128; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
                cross3(*a, *b, c) == [0, 0, 0] && dot(d, e) >= 0 && dot(d, e) <= dot(d, d)
            }
            ClosedShell::Polytope(r) => {
                let l: [i64; 3] = std::array::from_fn(|k| v[k] - r.bbox.origin[k]);
                if (0..3).any(|k| l[k] < 0 || l[k] >= r.bbox.dims[k] as i64) {
                    return false;
                }
                let s = r.spans[l[1] as usize + r.bbox.dims[1] * l[2] as usize];
                i64::from(s[0]) <= l[0] && l[0] <= i64::from(s[1])
            }
        }
    }
}

/// The shell tree as [`Polyhedron::voxelize`] reads it, one voxel at a
/// time, with a grid over the query box listing the shells whose bounding
/// box meets each cell.
struct ShellTree {
    shells: Vec<ClosedShell>,
    parent: Vec<Option<usize>>,
    /// Cells of [`GRID_CELL`]³ voxels, x fastest, from the box origin.
    cells: Vec<Vec<usize>>,
    origin: [i64; 3],
    n_cells: [usize; 3],
}

/// Edge of a grid cell of [`ShellTree`], in voxels.
const GRID_CELL: usize = 8;

impl ShellTree {
    fn of(p: &Polyhedron, bbox: &VoxelBox, backend: Backend<'_>) -> crate::Result<ShellTree> {
        let mut parent = Vec::with_capacity(p.shells.len());
        for (i, s) in p.shells.iter().enumerate() {
            match s.parent {
                Some(q) if (q as usize) < i => parent.push(Some(q as usize)),
                Some(q) => {
                    return Err(crate::Error::data(
                        "polyhedron",
                        "shell",
                        i,
                        format!("parent {q} does not come before it"),
                    ));
                }
                None => parent.push(None),
            }
        }
        let n_cells = bbox.dims.map(|d| d.div_ceil(GRID_CELL));
        let mut cells = vec![Vec::new(); n_cells.iter().product()];
        let shells = p
            .shells
            .iter()
            .map(|s| ClosedShell::of(&s.geometry, backend))
            .collect::<crate::Result<Vec<ClosedShell>>>()?;
        for (i, s) in shells.iter().enumerate() {
            let (lo, hi) = s.voxel_bounds();
            // Grid cells meeting the voxel range [lo, hi].
            let range = |a: usize| {
                let g = GRID_CELL as i128;
                let vlo = i128::from(lo[a]) - i128::from(bbox.origin[a]);
                let vhi = i128::from(hi[a]) - i128::from(bbox.origin[a]);
                let clo = vlo.max(0).div_euclid(g);
                let chi = vhi.min(bbox.dims[a] as i128 - 1).div_euclid(g);
                (clo as usize, if vlo > vhi { -1 } else { chi })
            };
            let (rx, ry, rz) = (range(0), range(1), range(2));
            if rx.1 < 0 || ry.1 < 0 || rz.1 < 0 {
                continue;
            }
            for cz in rz.0..=rz.1 as usize {
                for cy in ry.0..=ry.1 as usize {
                    for cx in rx.0..=rx.1 as usize {
                        cells[cx + n_cells[0] * (cy + n_cells[1] * cz)].push(i);
                    }
                }
            }
        }
        Ok(ShellTree {
            shells,
            parent,
            cells,
            origin: bbox.origin,
            n_cells,
        })
    }

    /// Whether the polyhedron holds voxel `v` of the box: some root region
    /// holds its centre, a region being the closed shell minus the
    /// children's regions (decided bottom-up over the shells containing
    /// the centre; a child comes after its parent).
    fn holds(&self, v: [i64; 3]) -> bool {
        let cell: [usize; 3] =
            std::array::from_fn(|a| (v[a] - self.origin[a]) as usize / GRID_CELL);
        let list = &self.cells[cell[0] + self.n_cells[0] * (cell[1] + self.n_cells[1] * cell[2])];
        let containing: Vec<usize> = list
            .iter()
            .copied()
            .filter(|&i| self.shells[i].contains(v))
            .collect();
        let mut region = vec![true; containing.len()];
        for k in (0..containing.len()).rev() {
            if region[k]
                && let Some(p) = self.parent[containing[k]]
                && let Ok(pk) = containing.binary_search(&p)
            {
                region[pk] = false;
            }
        }
        (0..containing.len()).any(|k| region[k] && self.parent[containing[k]].is_none())
    }
}

impl Polyhedron {
    /// Which voxels of `bbox` the polyhedron holds, by ray parity on its
    /// merged surface `surface` (module docs): inside by
    /// [`MergedSurface::classify`], except voxels on the surface or in a
    /// lower-dimensional shell, which the shell tree decides (closed tests
    /// of the polytopes by per-row spans on `backend`, looked up through a
    /// grid of the shells' boxes). One flag per voxel, x fastest; equal
    /// to [`Polyhedron::voxelize`] on every object tested (a check, not a
    /// proof: `chisel polyhedrize --verify` runs it every time).
    ///
    /// Errors: as [`MergedSurface::classify`]; hull-scan range limits; a
    /// malformed tree (a child listed before its parent).
    pub fn voxelize_ray_parity(
        &self,
        surface: &MergedSurface,
        bbox: &VoxelBox,
        backend: Backend<'_>,
    ) -> crate::Result<Vec<bool>> {
        let sides = surface.classify(bbox)?;
        let tree = ShellTree::of(self, bbox, backend)?;
        let mut labelled: Vec<bool> = sides.iter().map(|&s| s == Side::On).collect();
        for s in &self.shells {
            if s.geometry.dimension() < 3 {
                let (sb, flags) = s.geometry.closed_voxels(backend)?;
                for (k, &f) in flags.iter().enumerate() {
                    if f && let Some(i) = local_index(bbox, voxel_at(&sb, k)) {
                        labelled[i] = true;
                    }
                }
            }
        }
        Ok(sides
            .iter()
            .enumerate()
            .map(|(k, &side)| {
                if labelled[k] {
                    tree.holds(voxel_at(bbox, k))
                } else {
                    side == Side::Inside
                }
            })
            .collect())
    }

    /// [`Polyhedron::mismatches`] by ray parity: the voxels of the object's
    /// box plus a one-voxel margin where
    /// [`Polyhedron::voxelize_ray_parity`] differs from `object` (count,
    /// and the first `limit`).
    ///
    /// Errors: as [`Polyhedron::voxelize_ray_parity`].
    pub fn mismatches_ray_parity(
        &self,
        surface: &MergedSurface,
        object: &DigitalObject,
        backend: Backend<'_>,
        limit: usize,
    ) -> crate::Result<(u64, Vec<[i64; 3]>)> {
        let bbox = verify_box(object);
        let held = self.voxelize_ray_parity(surface, &bbox, backend)?;
        Ok(differences(object, &bbox, &held, limit))
    }
}

fn local_index(bbox: &VoxelBox, v: [i64; 3]) -> Option<usize> {
    let l: [i64; 3] = std::array::from_fn(|a| v[a] - bbox.origin[a]);
    if (0..3).any(|a| l[a] < 0 || l[a] >= bbox.dims[a] as i64) {
        return None;
    }
    Some(l[0] as usize + bbox.dims[0] * (l[1] as usize + bbox.dims[1] * l[2] as usize))
}
