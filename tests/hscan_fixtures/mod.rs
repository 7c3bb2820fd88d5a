//! Exact polyhedra for the hull-scan tests (`tests/hull_scan.rs`,
//! `tests/parity/hull_scan.rs`), built by brute force in i128 — test-only
//! stand-ins for the exact hull of `src/hull`.
//!
//! A polytope is given by supporting half-spaces in chosen directions
//! (offset = max of `n·p` over the points, so every point is inside); its
//! vertices are enumerated from all plane triples (Cramer's rule, exact
//! rationals), which yields the real faces (≥ 3 vertices) and their edge
//! adjacency (faces sharing two vertices). When every vertex is one of the
//! points, the polytope is exactly their convex hull ([`Polytope::is_hull_of`]).
#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::collections::{BTreeMap, BTreeSet, HashSet};

use chisel::hull_scan::{HalfSpace, VoxelBox};

/// xorshift64 (reproducible, no external RNG).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).max(1))
    }
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// Uniform in `lo..=hi`.
    pub fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next() % (hi - lo + 1) as u64) as i64
    }
}

fn gcd(a: i128, b: i128) -> i128 {
    let (mut a, mut b) = (a.abs(), b.abs());
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Primitive integer directions with components in `-k..=k`.
pub fn directions(k: i64) -> Vec<[i64; 3]> {
    let mut out = Vec::new();
    for a in -k..=k {
        for b in -k..=k {
            for c in -k..=k {
                if (a, b, c) != (0, 0, 0) && gcd(gcd(a.into(), b.into()), c.into()) == 1 {
                    out.push([a, b, c]);
                }
            }
        }
    }
    out
}

/// The 26 directions of the 26-neighbourhood (faces, edges, corners).
pub fn dirs26() -> Vec<[i64; 3]> {
    directions(1)
}

/// Supporting half-spaces of `points` in `dirs`: `n·p ≤ max_q n·q`.
pub fn supporting(points: &[[i64; 3]], dirs: &[[i64; 3]]) -> Vec<HalfSpace> {
    dirs.iter()
        .map(|&n| HalfSpace {
            normal: n,
            offset: points
                .iter()
                .map(|p| n[0] * p[0] + n[1] * p[1] + n[2] * p[2])
                .max()
                .expect("points"),
        })
        .collect()
}

/// Combinatorial voxel centres of the voxels of `object` (x fastest) in `bbox`.
pub fn centres(object: &[bool], bbox: &VoxelBox) -> Vec<[i64; 3]> {
    let [nx, ny, _] = bbox.dims;
    object
        .iter()
        .enumerate()
        .filter(|(_, o)| **o)
        .map(|(i, _)| bbox.centre([i % nx, (i / nx) % ny, i / (nx * ny)]))
        .collect()
}

/// Voxels of `object` that are first or last of an object run along x, y
/// and z (hull vertices are among them).
pub fn extreme_centres(object: &[bool], bbox: &VoxelBox) -> Vec<[i64; 3]> {
    let [nx, ny, nz] = bbox.dims;
    let at = |x: i64, y: i64, z: i64| {
        x >= 0
            && y >= 0
            && z >= 0
            && (x as usize) < nx
            && (y as usize) < ny
            && (z as usize) < nz
            && object[x as usize + nx * (y as usize + ny * z as usize)]
    };
    let mut out = Vec::new();
    for z in 0..nz as i64 {
        for y in 0..ny as i64 {
            for x in 0..nx as i64 {
                if at(x, y, z)
                    && (!at(x - 1, y, z) || !at(x + 1, y, z))
                    && (!at(x, y - 1, z) || !at(x, y + 1, z))
                    && (!at(x, y, z - 1) || !at(x, y, z + 1))
                {
                    out.push(bbox.centre([x as usize, y as usize, z as usize]));
                }
            }
        }
    }
    out
}

/// A bounded polytope from half-spaces, with its vertices and face graph.
#[derive(Debug, Clone)]
pub struct Polytope {
    /// The irredundant faces (≥ 3 vertices each), deduplicated.
    pub faces: Vec<HalfSpace>,
    /// `adjacency[f]`: faces sharing an edge (two vertices) with face `f`.
    pub adjacency: Vec<Vec<usize>>,
    /// Vertices as `(numerators, denominator > 0)`, reduced.
    pub vertices: Vec<([i128; 3], i128)>,
    /// `face_vertices[f]`: indices into `vertices`.
    pub face_vertices: Vec<Vec<usize>>,
}

impl Polytope {
    /// Vertex enumeration over all plane triples (O(F⁴); F up to ~100).
    pub fn new(half_spaces: &[HalfSpace]) -> Self {
        let mut seen = HashSet::new();
        let planes: Vec<HalfSpace> = half_spaces
            .iter()
            .filter(|h| {
                let g = h.normal.iter().fold(0i128, |g, &c| gcd(g, c.into()));
                if g == 0 {
                    return false;
                }
                // The plane n/g · p ≤ d/g, offset as a reduced fraction.
                let d = i128::from(h.offset);
                let e = gcd(d, g).max(1);
                seen.insert((h.normal.map(|c| i128::from(c) / g), d / e, g / e))
            })
            .copied()
            .collect();
        let n = planes.len();
        let mut vmap: BTreeMap<([i128; 3], i128), BTreeSet<usize>> = BTreeMap::new();
        let row = |h: &HalfSpace| h.normal.map(i128::from);
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let (a, b, c) = (row(&planes[i]), row(&planes[j]), row(&planes[k]));
                    let d = [planes[i].offset, planes[j].offset, planes[k].offset].map(i128::from);
                    let det3 = |a: [i128; 3], b: [i128; 3], c: [i128; 3]| {
                        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                            + a[2] * (b[0] * c[1] - b[1] * c[0])
                    };
                    let den = det3(a, b, c);
                    if den == 0 {
                        continue;
                    }
                    let col = |m: [i128; 3], t: usize| {
                        let mut m = m;
                        m[t] = 0;
                        m
                    };
                    let mut num = [0i128; 3];
                    for (t, slot) in num.iter_mut().enumerate() {
                        let (mut a2, mut b2, mut c2) = (col(a, t), col(b, t), col(c, t));
                        a2[t] = d[0];
                        b2[t] = d[1];
                        c2[t] = d[2];
                        *slot = det3(a2, b2, c2);
                    }
                    let (num, den) = if den < 0 {
                        (num.map(|v| -v), -den)
                    } else {
                        (num, den)
                    };
                    let g = num.iter().fold(den, |g, &v| gcd(g, v));
                    let (num, den) = (num.map(|v| v / g), den / g);
                    let on: Vec<usize> = (0..n)
                        .filter(|&f| {
                            let nf = row(&planes[f]);
                            let s = nf[0] * num[0] + nf[1] * num[1] + nf[2] * num[2]
                                - i128::from(planes[f].offset) * den;
                            s == 0
                        })
                        .collect();
                    let feasible = (0..n).all(|f| {
                        let nf = row(&planes[f]);
                        nf[0] * num[0] + nf[1] * num[1] + nf[2] * num[2]
                            <= i128::from(planes[f].offset) * den
                    });
                    if feasible {
                        vmap.entry((num, den)).or_default().extend(on);
                    }
                }
            }
        }
        let vertices: Vec<([i128; 3], i128)> = vmap.keys().copied().collect();
        let mut per_plane: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (v, on) in vmap.values().enumerate() {
            for &f in on {
                per_plane[f].push(v);
            }
        }
        let kept: Vec<usize> = (0..n).filter(|&f| per_plane[f].len() >= 3).collect();
        let faces: Vec<HalfSpace> = kept.iter().map(|&f| planes[f]).collect();
        let face_vertices: Vec<Vec<usize>> = kept.iter().map(|&f| per_plane[f].clone()).collect();
        let adjacency = (0..kept.len())
            .map(|f| {
                (0..kept.len())
                    .filter(|&g| {
                        g != f
                            && face_vertices[f]
                                .iter()
                                .filter(|v| face_vertices[g].contains(v))
                                .count()
                                >= 2
                    })
                    .collect()
            })
            .collect();
        Polytope {
            faces,
            adjacency,
            vertices,
            face_vertices,
        }
    }

    /// Whether every vertex is an integer point of `points` (then the
    /// polytope, which contains the points, is exactly their convex hull).
    pub fn is_hull_of(&self, points: &[[i64; 3]]) -> bool {
        let set: HashSet<[i64; 3]> = points.iter().copied().collect();
        self.vertices.iter().all(|(num, den)| {
            *den == 1 && set.contains(&num.map(|v| i64::try_from(v).expect("vertex")))
        })
    }
}

/// The six half-spaces of the voxel-centre box of voxels `lo ..= hi`
/// (hull of a box of voxels, vertices at voxel centres).
pub fn box_faces(lo: [i64; 3], hi: [i64; 3]) -> Vec<HalfSpace> {
    let mut out = Vec::new();
    for a in 0..3 {
        let mut n = [0i64; 3];
        n[a] = -1;
        out.push(HalfSpace {
            normal: n,
            offset: -(2 * lo[a] + 1),
        });
        n[a] = 1;
        out.push(HalfSpace {
            normal: n,
            offset: 2 * hi[a] + 1,
        });
    }
    out
}

/// Random half-spaces whose planes pass near the middle of `bbox`
/// (normals in `-k..=k`, some zero components), possibly unbounded or empty
/// inside the box — every case the scan must handle.
pub fn random_half_spaces(rng: &mut Rng, n: usize, bbox: &VoxelBox, k: i64) -> Vec<HalfSpace> {
    (0..n)
        .map(|_| {
            let mut normal = [rng.range(-k, k), rng.range(-k, k), rng.range(-k, k)];
            if rng.next().is_multiple_of(4) {
                normal[(rng.next() % 3) as usize] = 0;
            }
            let p: [i64; 3] = std::array::from_fn(|a| {
                let lo = 2 * bbox.origin[a];
                let hi = 2 * (bbox.origin[a] + bbox.dims[a] as i64);
                rng.range(lo, hi)
            });
            HalfSpace {
                normal,
                offset: normal[0] * p[0] + normal[1] * p[1] + normal[2] * p[2],
            }
        })
        .collect()
}

/// Digital ball: voxels of a `n³` box whose centre lies within combinatorial
/// radius `r` of the box centre (`|2p − c|² ≤ r²` in combinatorial units).
pub fn digital_ball(n: usize, r: i64) -> (Vec<bool>, VoxelBox) {
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [n; 3],
    };
    let c = n as i64;
    let mut obj = vec![false; n * n * n];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = bbox.centre([x, y, z]);
                let d2: i64 = p.iter().map(|v| (v - c) * (v - c)).sum();
                obj[x + n * (y + n * z)] = d2 <= r * r;
            }
        }
    }
    (obj, bbox)
}

/// The exact hull of the cube with corners at combinatorial 1 and 9: its
/// half-spaces, their faces' z ranges (`ConvexHull::face_z_extents`), and
/// the 6³ voxel box at the origin around it — the culling negative
/// controls' case.
pub fn cube_hull() -> (Vec<HalfSpace>, Vec<[i64; 2]>, VoxelBox) {
    let points: Vec<[i64; 3]> = (0..8)
        .map(|k| std::array::from_fn(|a| if k >> a & 1 == 1 { 9 } else { 1 }))
        .collect();
    let hull = chisel::hull::ConvexHull::build(&points, Default::default()).unwrap();
    let faces = hull.half_spaces().into_iter().map(Into::into).collect();
    let bbox = VoxelBox {
        origin: [0; 3],
        dims: [6; 3],
    };
    (faces, hull.face_z_extents(), bbox)
}
