//! Distances from points to a triangle mesh, and the symmetric Hausdorff
//! distance between two meshes (over their vertices), with a uniform grid
//! of triangle boxes as the broad phase.

use glam::{DVec3, IVec3, Vec3};

use super::TriMesh;

/// Closest point to `p` on triangle (a, b, c) (Ericson, Real-Time
/// Collision Detection §5.1.5: Voronoi regions of the corners and edges).
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // Degenerate triangle: the nearest of its edges' closest points.
        let seg = |u: DVec3, v: DVec3| {
            let d = v - u;
            let t = if d.length_squared() > 0.0 {
                ((p - u).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            u + t * d
        };
        return [seg(a, b), seg(b, c), seg(c, a)]
            .into_iter()
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// A mesh prepared for distance queries.
#[derive(Debug)]
pub struct DistanceGrid<'a> {
    mesh: &'a TriMesh,
    origin: Vec3,
    cell: f32,
    dims: IVec3,
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl<'a> DistanceGrid<'a> {
    /// Grids the triangles' boxes with cells about twice the mean edge.
    pub fn new(mesh: &'a TriMesh) -> DistanceGrid<'a> {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let mut edge = 0.0f64;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            lo = lo.min(a.min(b).min(c));
            hi = hi.max(a.max(b).max(c));
            edge += f64::from(a.distance(b) + b.distance(c) + c.distance(a));
        }
        let n = mesh.triangles.len().max(1);
        let mut cell = (2.0 * edge / (3 * n) as f64).max(1e-9) as f32;
        let count = |c: f32| {
            ((hi - lo).max(Vec3::ZERO) / c)
                .floor()
                .min(Vec3::splat(1e6))
                .as_ivec3()
                + IVec3::ONE
        };
        while count(cell).as_dvec3().element_product() > (8 * n) as f64 {
            cell *= 1.25;
        }
        let dims = if mesh.triangles.is_empty() {
            IVec3::ONE
        } else {
            count(cell)
        };
        let lo = if mesh.triangles.is_empty() {
            Vec3::ZERO
        } else {
            lo
        };
        let at = |p: Vec3| {
            ((p - lo) / cell)
                .floor()
                .as_ivec3()
                .clamp(IVec3::ZERO, dims - 1)
        };
        let idx = |c: IVec3| (c.x + dims.x * (c.y + dims.y * c.z)) as usize;
        let n_cells = (dims.x * dims.y * dims.z) as usize;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_cells];
        for (i, t) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let (c0, c1) = (at(a.min(b).min(c)), at(a.max(b).max(c)));
            for z in c0.z..=c1.z {
                for y in c0.y..=c1.y {
                    for x in c0.x..=c1.x {
                        lists[idx(IVec3::new(x, y, z))].push(i as u32);
                    }
                }
            }
        }
        let mut starts = vec![0u32];
        let mut items = Vec::new();
        for l in lists {
            items.extend(l);
            starts.push(items.len() as u32);
        }
        DistanceGrid {
            mesh,
            origin: lo,
            cell,
            dims,
            starts,
            items,
        }
    }

    /// Distance from `p` to the mesh (infinite for a mesh without
    /// triangles): rings of cells around p's cell until the nearest
    /// triangle found is closer than the rings cover.
    pub fn distance(&self, p: Vec3) -> f64 {
        if self.mesh.triangles.is_empty() {
            return f64::INFINITY;
        }
        let c = ((p - self.origin) / self.cell)
            .floor()
            .as_ivec3()
            .clamp(IVec3::ZERO, self.dims - 1);
        let mut best = f64::INFINITY;
        let max_ring = self.dims.max_element();
        for ring in 0..=max_ring {
            for z in (c.z - ring).max(0)..=(c.z + ring).min(self.dims.z - 1) {
                for y in (c.y - ring).max(0)..=(c.y + ring).min(self.dims.y - 1) {
                    for x in (c.x - ring).max(0)..=(c.x + ring).min(self.dims.x - 1) {
                        let q = IVec3::new(x, y, z);
                        if (q - c).abs().max_element() != ring {
                            continue;
                        }
                        let k = (x + self.dims.x * (y + self.dims.y * z)) as usize;
                        for &t in &self.items[self.starts[k] as usize..self.starts[k + 1] as usize]
                        {
                            let [a, b, cc] = self.mesh.triangles[t as usize]
                                .map(|v| self.mesh.positions[v as usize].as_dvec3());
                            let d =
                                closest_on_triangle(p.as_dvec3(), a, b, cc).distance(p.as_dvec3());
                            best = best.min(d);
                        }
                    }
                }
            }
            // Every triangle not yet seen touches only cells more than
            // `ring` cells from p's (clamped) cell: at least ring·cell away.
            if best <= f64::from(ring as f32 * self.cell) {
                break;
            }
        }
        best
    }
}

/// The symmetric Hausdorff distance over vertices: the largest distance
/// from a vertex of either mesh to the other mesh.
pub fn hausdorff(a: &TriMesh, b: &TriMesh) -> f64 {
    use rayon::prelude::*;
    let one_way = |from: &TriMesh, to: &TriMesh| {
        let grid = DistanceGrid::new(to);
        from.positions
            .par_iter()
            .map(|p| grid.distance(*p))
            .reduce(|| 0.0, f64::max)
    };
    one_way(a, b).max(one_way(b, a))
}
