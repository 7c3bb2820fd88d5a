//! Fusion of a mesh that is not star-shaped about H with one that is
//! (seed 001 §2.6.2).
//!
//! From H ∈ A ∩ B a ray crosses the star-shaped B once, at parameter t_B,
//! but may cross A several times: along it A is the intervals [0, t₁],
//! [t₂, t₃], … and holds (t_end³ − t_start³)/3 of volume per unit solid
//! angle in each. vol(A) + vol(B) counts the overlap A ∩ B twice; the seed
//! moves this excess, E = Σ (min(t_end, t_B)³ − min(t_start, t_B)³), into
//! the first empty segment of the ray (from the first exit of A ∪ B
//! outward), what does not fit into the next empty segment, and so on. C
//! along the ray is A ∪ B with these fills ([`intervals`]): it contains
//! A ∪ B and holds exactly vol(A) + vol(B) in every cone of directions.
//! Where A is star-shaped too this is eq. 5 again.
//!
//! The seed deforms a copy of A until it approximates C; but a fill that
//! closes a gap joins two layers of A, so C's topology is not A's. Here C
//! is the zero set of g, the signed distance along the ray through a point
//! to C's nearest boundary (positive inside), sampled on a grid whose cell
//! is C's longest box side over [`FuseOptions::cells`](super::FuseOptions)
//! and meshed by the engine's marching cubes (closed, outward, one vertex
//! per crossed grid edge). Each vertex then moves along its grid edge onto
//! the surface by [`CROSSING_STEPS`] steps on g (Illinois secant steps
//! alternating with bisections; rays again).
//!
//! Guarantees: C's mesh is closed and wound outward (marching cubes), and
//! holds vol(A) + vol(B) up to the grid's discretisation. B's surface never
//! is C's boundary (the fill starts at the first exit of A ∪ B), so B lies
//! strictly inside C once the grid resolves the fill. But beyond the fill
//! C's boundary *is* A's surface, and a chord surface of it cuts A's convex
//! vertices by up to their sagitta: the exact test ([`super::contain`])
//! counts the vertices of A and B outside C's mesh and the report gives
//! their largest distance (growing C to cover them would cost
//! vol(C) about that distance times A's exposed area).
//!
//! The conditions are checked on every ray and refused otherwise: B
//! crossed once (`NotStarShaped`), A an odd number of times
//! (`OpenAlongRays`: H outside A, or A open), and A ∩ B one connected piece
//! at the grid's resolution (its grid points 6-connected;
//! `IntersectionNotConnected`), as the seed requires.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::radial::EXAMPLES;
use super::{Pass, contain, used_positions};
use crate::foundation::UnionFind;
use crate::gpu::Backend;
use crate::mc::{IsoSpec, McOptions, marching_cubes};
use crate::mesh::distance::DistanceGrid;
use crate::mesh::{TriMesh, unit_icosphere};
use crate::ray_cast::{Bvh, RayCaster};
use crate::volume::{Volume, VolumeData};
use crate::{Error, Refusal, Result};

/// Default grid cells along C's longest box side.
pub const CELLS: usize = 128;
/// Most grid points.
pub const MAX_GRID_POINTS: usize = 1 << 27;
/// Steps that move each vertex onto C along its grid edge (Illinois
/// secant steps alternating with bisections).
pub const CROSSING_STEPS: usize = 6;
/// Icosphere level of the directions that find C's extent.
const PROBE_LEVEL: u32 = 4;
/// Most times the grid's box grows when C reaches its border.
const BOX_ROUNDS: usize = 3;
/// Grid points per batch of rays.
const BATCH: usize = 1 << 20;
/// Relative margin around C's probed box.
const MARGIN: f64 = 0.1;

/// What the layered construction did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LayeredReport {
    /// The input that is not star-shaped about H ("A" or "B").
    pub not_star_shaped: &'static str,
    /// Grid points per axis.
    pub grid: [usize; 3],
    /// Grid cell (input units).
    pub cell: f64,
    /// Rays cast for the grid (both meshes).
    pub grid_rays: usize,
    /// Rays cast to move vertices onto C (both meshes).
    pub crossing_rays: usize,
    /// Widest bracket about a vertex's crossing after the steps (input
    /// units): where g jumps (a layer of A appears between neighbouring
    /// rays) the crossing is the jump, located to this width.
    pub crossing_bracket: f64,
    /// Largest distance from C of a vertex of A or B outside it (input
    /// units; 0 when none is): where C's boundary is A's surface, C's chords
    /// cut A's convex vertices by up to their sagitta.
    pub outside_distance: f64,
    /// Times the box grew because C reached its border.
    pub box_rounds: usize,
}

/// C's intervals along one ray (parameters, ascending, disjoint) from the
/// sorted hits `a` of the mesh that need not be star-shaped (an odd count:
/// H inside) and the one hit `tb` of the star-shaped one.
pub fn intervals(a: &[f64], tb: f64) -> Vec<[f64; 2]> {
    let cube = |t: f64| t * t * t;
    let layers = std::iter::once([0.0, a[0]]).chain(a[1..].chunks_exact(2).map(|c| [c[0], c[1]]));
    let mut excess = 0.0;
    let mut out: Vec<[f64; 2]> = vec![[0.0, tb]];
    for [s, e] in layers {
        excess += cube(e.min(tb)) - cube(s.min(tb));
        let last = out.last_mut().expect("starts with B");
        if s <= last[1] {
            last[1] = last[1].max(e);
        } else {
            out.push([s, e]);
        }
    }
    // The fill grows the interval that holds H: it fills the first gap,
    // merges with the layer beyond, fills the next gap, and so on.
    while excess > 0.0 {
        let g0 = cube(out[0][1]);
        match out.get(1) {
            Some(&[next, end]) if cube(next) - g0 <= excess => {
                excess -= cube(next) - g0;
                out[0][1] = end;
                out.remove(1);
            }
            _ => {
                out[0][1] = (g0 + excess).cbrt();
                excess = 0.0;
            }
        }
    }
    out
}

/// The signed distance (parameters, positive inside) from parameter 1 to
/// the nearest boundary of `c` (H's end at 0 is none).
fn signed_at_one(c: &[[f64; 2]]) -> f64 {
    let inside = c.iter().any(|&[s, e]| s <= 1.0 && 1.0 <= e);
    let nearest = c
        .iter()
        .enumerate()
        .flat_map(|(i, &[s, e])| [(i > 0).then_some(s), Some(e)])
        .flatten()
        .map(|b| (b - 1.0).abs())
        .fold(f64::INFINITY, f64::min);
    if inside { nearest } else { -nearest }
}

/// The first failing rays of `bad` for a refusal: unit direction, hits.
fn examples(
    dirs: &[[f32; 4]],
    bad: &[usize],
    count: impl Fn(usize) -> u32,
) -> Vec<([f32; 3], u32)> {
    bad.iter()
        .take(EXAMPLES)
        .map(|&i| {
            let d = Vec3::new(dirs[i][0], dirs[i][1], dirs[i][2]).normalize_or_zero();
            (d.to_array(), count(i))
        })
        .collect()
}

/// What C and the inputs are at one point.
#[derive(Debug, Clone, Copy)]
struct Sample {
    /// g (input units).
    g: f64,
    /// Inside the mesh that need not be star-shaped, and inside the other.
    in_a: bool,
    in_b: bool,
}

/// The two casters about H, and the rays cast.
struct Field<'a> {
    /// The mesh that need not be star-shaped, its name and caster.
    a: (&'static str, &'a RayCaster<'a>),
    /// The star-shaped mesh.
    b: (&'static str, &'a RayCaster<'a>),
    center: Vec3,
    rays: usize,
}

impl Field<'_> {
    /// C's intervals along every direction of `dirs` (any length;
    /// parameters in its units) mapped by `f` with the parameter of B's hit
    /// and the sorted hits of A.
    fn along<T: Send>(
        &mut self,
        dirs: &[[f32; 4]],
        f: impl Fn(&[[f64; 2]], f64, &[f64]) -> T + Sync,
    ) -> Result<Vec<T>> {
        let ha = self.a.1.hits(self.center, dirs)?;
        let hb = self.b.1.cast(self.center, dirs)?;
        self.rays += 2 * dirs.len();
        let real = |i: usize| dirs[i][..3].iter().any(|&v| v != 0.0);
        let center = self.center.as_dvec3().to_array();
        let bad_b: Vec<usize> = (0..dirs.len())
            .filter(|&i| real(i) && hb[i].count != 1)
            .collect();
        if !bad_b.is_empty() {
            return Err(Refusal::NotStarShaped {
                mesh: self.b.0,
                center,
                failing: bad_b.len(),
                rays: dirs.len(),
                examples: examples(dirs, &bad_b, |i| hb[i].count),
            }
            .into());
        }
        let count_a = |i: usize| ha.offsets[i + 1] - ha.offsets[i];
        let bad_a: Vec<usize> = (0..dirs.len())
            .filter(|&i| real(i) && count_a(i) % 2 == 0)
            .collect();
        if !bad_a.is_empty() {
            return Err(Refusal::OpenAlongRays {
                mesh: self.a.0,
                center,
                failing: bad_a.len(),
                rays: dirs.len(),
                examples: examples(dirs, &bad_a, count_a),
            }
            .into());
        }
        Ok((0..dirs.len())
            .into_par_iter()
            .with_min_len(256)
            .map_init(Vec::new, |sorted, i| {
                if !real(i) {
                    // H itself: inside everything, far from C's boundary.
                    return f(&[[0.0, f64::INFINITY]], f64::INFINITY, &[f64::INFINITY]);
                }
                sorted.clear();
                sorted.extend(ha.of(i).iter().map(|h| f64::from(h.t)));
                sorted.sort_unstable_by(f64::total_cmp);
                let tb = f64::from(hb[i].far);
                f(&intervals(sorted, tb), tb, sorted)
            })
            .collect())
    }

    /// C and the inputs at `points`.
    fn sample(&mut self, points: &[DVec3]) -> Result<Vec<Sample>> {
        let h = self.center.as_dvec3();
        let dirs: Vec<[f32; 4]> = points
            .iter()
            .map(|p| {
                let d = (*p - h).as_vec3();
                [d.x, d.y, d.z, 0.0]
            })
            .collect();
        let samples = self.along(&dirs, |c, tb, a| {
            let in_a = a.iter().take_while(|&&t| t < 1.0).count() % 2 == 0;
            (signed_at_one(c), in_a, 1.0 < tb)
        })?;
        Ok(samples
            .into_iter()
            .zip(&dirs)
            .map(|((g, in_a, in_b), d)| Sample {
                // (H itself: g = ∞ stays, the direction has no length.)
                g: if g.is_finite() {
                    g * f64::from(Vec3::new(d[0], d[1], d[2]).length())
                } else {
                    g
                },
                in_a,
                in_b,
            })
            .collect())
    }
}

/// The grid: corner, cell and points per axis.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
}

impl Grid {
    /// Points every `cell` from `lo` to at least `hi`.
    fn new(lo: DVec3, hi: DVec3, cell: f64) -> Result<Grid> {
        let dims = ((hi - lo) / cell).to_array().map(|e| e.ceil() as usize + 1);
        let n = dims.iter().product::<usize>();
        if n > MAX_GRID_POINTS {
            return Err(Error::limit(
                "fusion: grid points (lower the cells)",
                n,
                MAX_GRID_POINTS,
            ));
        }
        Ok(Grid { lo, cell, dims })
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    fn point(&self, i: usize) -> DVec3 {
        let [nx, ny, _] = self.dims;
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        self.lo + self.cell * DVec3::new(x as f64, y as f64, z as f64)
    }

    fn on_border(&self, i: usize) -> bool {
        let [nx, ny, nz] = self.dims;
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz
    }
}

/// The grid points of A ∩ B per 6-connected component, largest first.
fn intersection_components(grid: &Grid, both: &[bool]) -> Vec<usize> {
    let [nx, ny, _] = grid.dims;
    let mut uf: UnionFind = UnionFind::with_len(both.len());
    for i in (0..both.len()).filter(|&i| both[i]) {
        let (x, y) = (i % nx, (i / nx) % ny);
        for (ok, j) in [
            (x + 1 < nx, i + 1),
            (y + 1 < ny, i + nx),
            (true, i + nx * ny),
        ] {
            if ok && j < both.len() && both[j] {
                uf.union(i as u32, j as u32);
            }
        }
    }
    let mut sizes = std::collections::HashMap::new();
    for i in (0..both.len()).filter(|&i| both[i]) {
        *sizes.entry(uf.find(i as u32)).or_insert(0usize) += 1;
    }
    let mut out: Vec<usize> = sizes.into_values().collect();
    out.sort_unstable_by(|a, b| b.cmp(a));
    out
}

/// The fused mesh of the layered construction.
pub(super) struct Layered {
    pub mesh: TriMesh,
    pub report: LayeredReport,
    pub rays: usize,
    pub outside: usize,
}

/// Fuses `a` (need not be star-shaped about `center`) with `b` (must be);
/// `names` are their names in refusals and the report; `on_pass` sees one
/// pass at the end (its deviation is the widest crossing bracket).
pub(super) fn fuse_layered(
    a: (&TriMesh, &RayCaster<'_>),
    b: (&TriMesh, &RayCaster<'_>),
    names: [&'static str; 2],
    center: Vec3,
    cells: usize,
    backend: Backend<'_>,
    on_pass: &mut dyn FnMut(&Pass),
) -> Result<Layered> {
    if cells < 2 {
        return Err(Error::param("cells", cells, "at least 2"));
    }
    let mut field = Field {
        a: (names[0], a.1),
        b: (names[1], b.1),
        center,
        rays: 0,
    };
    // C's extent: A ∪ B and the far ends of C along probe directions.
    let h = center.as_dvec3();
    let (units, _) = unit_icosphere(PROBE_LEVEL);
    let probe: Vec<[f32; 4]> = units
        .iter()
        .map(|d| [d.x as f32, d.y as f32, d.z as f32, 0.0])
        .collect();
    let far = field.along(&probe, |c, _, _| c.last().map_or(0.0, |l| l[1]))?;
    let (mut lo, mut hi) = (h, h);
    for m in [a.0, b.0] {
        if let Some((l, u)) = m.bounds() {
            lo = lo.min(l.as_dvec3());
            hi = hi.max(u.as_dvec3());
        }
    }
    for (d, t) in units.iter().zip(far) {
        lo = lo.min(h + t * *d);
        hi = hi.max(h + t * *d);
    }
    let mut box_rounds = 0;
    let (grid, values, grid_rays) = loop {
        let extent = (hi - lo).max_element();
        let cell = extent * (1.0 + 2.0 * MARGIN) / cells as f64;
        let pad = DVec3::splat(MARGIN * extent + cell);
        let grid = Grid::new(lo - pad, hi + pad, cell)?;
        let before = field.rays;
        let mut values = Vec::with_capacity(grid.len());
        let mut both = Vec::with_capacity(grid.len());
        for start in (0..grid.len()).step_by(BATCH) {
            let points: Vec<DVec3> = (start..(start + BATCH).min(grid.len()))
                .map(|i| grid.point(i))
                .collect();
            for s in field.sample(&points)? {
                values.push(s.g.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32);
                both.push(s.in_a && s.in_b);
            }
        }
        let grid_rays = field.rays - before;
        let reaches = (0..grid.len()).any(|i| grid.on_border(i) && values[i] >= 0.0);
        if !reaches {
            let components = intersection_components(&grid, &both);
            if components.len() > 1 {
                return Err(Refusal::IntersectionNotConnected {
                    components: components.len(),
                    points: components.into_iter().take(EXAMPLES).collect(),
                    cell: grid.cell,
                }
                .into());
            }
            break (grid, values, grid_rays);
        }
        if box_rounds == BOX_ROUNDS {
            return Err(Error::Internal(format!(
                "fusion: C still reaches the border of a grid grown {BOX_ROUNDS} times"
            )));
        }
        box_rounds += 1;
        let mid = (lo + hi) * 0.5;
        (lo, hi) = (mid + (lo - mid) * 1.5, mid + (hi - mid) * 1.5);
    };

    let volume = Volume::new(
        grid.dims,
        [grid.cell; 3],
        grid.lo.to_array(),
        VolumeData::F32(values),
    )?;
    let surface = marching_cubes(&volume, IsoSpec::Level(0.0), &McOptions::default(), backend)?;
    let VolumeData::F32(values) = &volume.data else {
        unreachable!("built from f32 samples")
    };
    let mut mesh = surface.mesh;
    let before = field.rays;
    let bracket = onto_surface(&mut field, &grid, values, &surface.vertex_edges, &mut mesh)?;
    let crossing_rays = field.rays - before;

    // Containment, exactly; the distance of any vertex outside.
    let points: Vec<Vec3> = used_positions(a.0)
        .into_iter()
        .chain(used_positions(b.0))
        .collect();
    let bvh = Bvh::build(&mesh)?;
    let caster = RayCaster::new(&bvh, backend)?;
    let outside = contain::outside(&mesh, &caster, center, &points)?;
    let distances = DistanceGrid::new(&mesh);
    let outside_distance = outside
        .par_iter()
        .map(|o| distances.distance(points[o.point]))
        .reduce(|| 0.0, f64::max);
    on_pass(&Pass {
        triangles: mesh.triangles.len(),
        directions: field.rays,
        marked: outside.len(),
        max_deviation: bracket,
    });
    Ok(Layered {
        mesh,
        report: LayeredReport {
            not_star_shaped: names[0],
            grid: grid.dims,
            cell: grid.cell,
            grid_rays,
            crossing_rays,
            crossing_bracket: bracket,
            outside_distance,
            box_rounds,
        },
        rays: field.rays,
        outside: outside.len(),
    })
}

/// Moves every vertex of `mesh` (on grid edge `edges[v]` = 3·point + axis)
/// onto g = 0 along its edge by [`CROSSING_STEPS`] steps; returns the
/// widest bracket left (input units).
fn onto_surface(
    field: &mut Field<'_>,
    grid: &Grid,
    values: &[f32],
    edges: &[u64],
    mesh: &mut TriMesh,
) -> Result<f64> {
    let [nx, ny, _] = grid.dims;
    let stride = [1, nx, nx * ny];
    // Per vertex: the edge's ends, the bracket (s, f) at both ends, and
    // which end the last step replaced (Illinois halves the other's f).
    struct Bracket {
        p0: DVec3,
        axis: usize,
        lo: (f64, f64),
        hi: (f64, f64),
        last: i8,
    }
    let mut brackets: Vec<Bracket> = edges
        .iter()
        .map(|&e| {
            let (point, axis) = ((e / 3) as usize, (e % 3) as usize);
            let f0 = f64::from(values[point]);
            let f1 = f64::from(values[point + stride[axis]]);
            Bracket {
                p0: grid.point(point),
                axis,
                lo: (0.0, f0),
                hi: (1.0, f1),
                last: 0,
            }
        })
        .collect();
    // The secant's zero, kept off the bracket's ends (and the grid points).
    let secant = |b: &Bracket| {
        let ((s0, f0), (s1, f1)) = (b.lo, b.hi);
        let s = if f0 == f1 { 0.5 } else { f0 / (f0 - f1) };
        let keep = 1.0 / 64.0;
        s0 + (s1 - s0) * s.clamp(keep, 1.0 - keep)
    };
    let at = |b: &Bracket, s: f64| {
        let mut p = b.p0;
        p[b.axis] += s * grid.cell;
        p
    };
    for step in 0..CROSSING_STEPS {
        // Secant steps, every other one a bisection: where g jumps the
        // secant alone can creep.
        let s: Vec<f64> = if step % 2 == 1 {
            brackets.iter().map(|b| 0.5 * (b.lo.0 + b.hi.0)).collect()
        } else {
            brackets.iter().map(secant).collect()
        };
        let points: Vec<DVec3> = brackets.iter().zip(&s).map(|(b, &s)| at(b, s)).collect();
        let samples = field.sample(&points)?;
        for ((b, &s), sample) in brackets.iter_mut().zip(&s).zip(&samples) {
            let f = sample.g;
            if (f >= 0.0) == (b.lo.1 >= 0.0) {
                b.lo = (s, f);
                if b.last == -1 {
                    b.hi.1 *= 0.5;
                }
                b.last = -1;
            } else {
                b.hi = (s, f);
                if b.last == 1 {
                    b.lo.1 *= 0.5;
                }
                b.last = 1;
            }
        }
    }
    let bracket = brackets
        .iter()
        .map(|b| (b.hi.0 - b.lo.0).abs() * grid.cell)
        .fold(0.0, f64::max);
    for (p, b) in mesh.positions.iter_mut().zip(&brackets) {
        *p = at(b, secant(b)).as_vec3();
    }
    Ok(bracket)
}
