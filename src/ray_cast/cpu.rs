//! CPU mirror of `kernels/ray_cast.wgsl` and `kernels/ray_hits.wgsl`
//! (their shared tests in `kernels/shared/bvh_ray.wgsl`): the same walk,
//! the same f32 operations in the same order, one ray at a time (rays in
//! parallel).

use rayon::prelude::*;

use super::bvh::{Bvh, Node};
use super::{Hit, NO_TRIANGLE, RayHit};

/// Per-ray constants of the watertight test (Woop, Benthin & Wald 2013):
/// the axis `kz` of the direction's largest component, the shear that maps
/// the ray onto the +z axis, and the inverse direction of the box test with
/// the axes along which the ray is flat.
#[derive(Debug, Clone, Copy)]
struct Ray {
    origin: [f32; 3],
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
    inv: [f32; 3],
    flat: [bool; 3],
}

/// Direction components below this magnitude count as 0 in the box test
/// (the ray stays in its slab), so no `0 · ∞` appears.
const TINY: f32 = 1e-20;

/// Widening of the ray–box interval: 2⁻²⁰ of its far end.
const WIDEN: f32 = 1.0 + 1.0 / (1 << 20) as f32;

impl Ray {
    fn new(origin: [f32; 3], d: [f32; 3]) -> Ray {
        let a = d.map(f32::abs);
        let kz = if a[0] >= a[1] && a[0] >= a[2] {
            0
        } else if a[1] >= a[2] {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let flat = d.map(|v| v.abs() < TINY);
        Ray {
            origin,
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            inv: d.map(|v| 1.0 / v),
            flat,
        }
    }

    /// Whether the ray meets `node`'s box at a parameter ≥ 0 (slab test
    /// with the far end widened by [`WIDEN`]; along an axis where the
    /// direction is below [`TINY`], whether the origin is inside the slab).
    fn meets(&self, node: &Node) -> bool {
        let mut t_min = 0.0f32;
        let mut t_max = f32::MAX;
        for k in 0..3 {
            if self.flat[k] {
                if self.origin[k] < node.lo[k] || self.origin[k] > node.hi[k] {
                    return false;
                }
                continue;
            }
            let t1 = (node.lo[k] - self.origin[k]) * self.inv[k];
            let t2 = (node.hi[k] - self.origin[k]) * self.inv[k];
            t_min = t_min.max(t1.min(t2));
            t_max = t_max.min(t1.max(t2));
        }
        t_min <= t_max * WIDEN
    }

    /// The ray parameter of a hit on triangle `(p0, p1, p2)`, if any.
    fn hit(&self, p: [[f32; 4]; 3]) -> Option<f32> {
        let rel = p.map(|c| [0, 1, 2].map(|k| c[k] - self.origin[k]));
        // Sheared 2-D corners: the ray is the origin of this plane.
        let x = rel.map(|r| r[self.kx] - self.sx * r[self.kz]);
        let y = rel.map(|r| r[self.ky] - self.sy * r[self.kz]);
        // Edge functions of the directed edges 0→1, 1→2, 2→0: each is a
        // function of its two corners alone, negated exactly for the
        // neighbour that walks the edge the other way (watertightness).
        let e = [
            x[0] * y[1] - y[0] * x[1],
            x[1] * y[2] - y[1] * x[2],
            x[2] * y[0] - y[2] * x[0],
        ];
        let det = e[0] + e[1] + e[2];
        if det == 0.0 {
            return None;
        }
        let ccw = det > 0.0;
        for (i, &ei) in e.iter().enumerate() {
            let inside = if ccw { ei } else { -ei };
            if inside < 0.0 {
                return None;
            }
            if ei == 0.0 {
                // On the edge's line: only the triangle that walks the edge
                // (counter-clockwise) in a direction of angle [0, π) owns it.
                let j = (i + 1) % 3;
                let (mut vx, mut vy) = (x[j] - x[i], y[j] - y[i]);
                if !ccw {
                    (vx, vy) = (-vx, -vy);
                }
                if !(vy > 0.0 || (vy == 0.0 && vx > 0.0)) {
                    return None;
                }
            }
        }
        let z = rel.map(|r| self.sz * r[self.kz]);
        let t = (e[1] * z[0] + e[2] * z[1] + e[0] * z[2]) / det;
        (t > 0.0).then_some(t)
    }
}

/// Walks `bvh` along `ray` and calls `visit(t, triangle id)` for every hit,
/// in the kernels' order (boxes in preorder, triangles in leaf order).
fn walk(bvh: &Bvh, ray: &Ray, mut visit: impl FnMut(f32, u32)) {
    let mut i = 0usize;
    while i < bvh.nodes.len() {
        let node = &bvh.nodes[i];
        if !ray.meets(node) {
            i = node.escape as usize;
            continue;
        }
        if node.leaf == 0 {
            i += 1;
            continue;
        }
        for t in node.triangles() {
            let c = [0, 1, 2].map(|k| bvh.corners[3 * t + k]);
            if let Some(d) = ray.hit(c) {
                visit(d, c[0][3].to_bits());
            }
        }
        i = node.escape as usize;
    }
}

/// Casts one ray from `origin` along `dir` (any length; distances are in
/// units of its length) through `bvh`.
pub fn cast(bvh: &Bvh, origin: [f32; 3], dir: [f32; 3]) -> RayHit {
    let mut out = RayHit::MISS;
    walk(bvh, &Ray::new(origin, dir), |t, tri| out.add(t, tri));
    out
}

/// Casts every ray of `dirs` (`[x, y, z, _]`) from `origin`.
pub fn ray_cast(bvh: &Bvh, origin: [f32; 3], dirs: &[[f32; 4]]) -> Vec<RayHit> {
    dirs.par_iter()
        .with_min_len(64)
        .map(|d| cast(bvh, origin, [d[0], d[1], d[2]]))
        .collect()
}

/// Mirror of `kernels/ray_hits.wgsl`: every hit of every ray of `dirs`
/// from `origin`, ray `i`'s at `offsets[i] − offsets[0]…` in walk order
/// (writes past a ray's slots dropped), and the count each walk found.
pub fn ray_hits(
    bvh: &Bvh,
    origin: [f32; 3],
    dirs: &[[f32; 4]],
    offsets: &[u32],
) -> (Vec<Hit>, Vec<u32>) {
    assert_eq!(
        offsets.len(),
        dirs.len() + 1,
        "one offset per ray and the end"
    );
    let base = offsets[0];
    let total = (offsets[dirs.len()] - base) as usize;
    let mut hits = vec![
        Hit {
            t: 0.0,
            tri: NO_TRIANGLE
        };
        total
    ];
    // Each ray writes only its own slots: split the output by the offsets.
    let mut slices = Vec::with_capacity(dirs.len());
    let mut rest = hits.as_mut_slice();
    for w in offsets.windows(2) {
        let (mine, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
        slices.push(mine);
        rest = tail;
    }
    let counts = dirs
        .par_iter()
        .zip(slices)
        .with_min_len(64)
        .map(|(d, slots)| {
            let mut count = 0usize;
            walk(bvh, &Ray::new(origin, [d[0], d[1], d[2]]), |t, tri| {
                if let Some(slot) = slots.get_mut(count) {
                    *slot = Hit { t, tri };
                }
                count += 1;
            });
            count as u32
        })
        .collect();
    (hits, counts)
}

impl RayHit {
    /// No hit: counts 0, distances −1, triangles [`NO_TRIANGLE`].
    pub const MISS: RayHit = RayHit {
        near: -1.0,
        far: -1.0,
        near_tri: NO_TRIANGLE,
        far_tri: NO_TRIANGLE,
        count: 0,
    };

    /// Records a hit at `t` on triangle `tri` (ties on `t` go to the lower
    /// id, so the result does not depend on the walk's order).
    fn add(&mut self, t: f32, tri: u32) {
        if self.count == 0 || t < self.near || (t == self.near && tri < self.near_tri) {
            self.near = t;
            self.near_tri = tri;
        }
        if self.count == 0 || t > self.far || (t == self.far && tri < self.far_tri) {
            self.far = t;
            self.far_tri = tri;
        }
        self.count += 1;
    }
}
