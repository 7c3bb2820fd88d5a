//! Marching cubes: watertightness, orientation, welding, spacing/origin,
//! and group counts / per-group Euler characteristics against an
//! independent voxel-topology oracle (cubical complexes, below).

mod common;

use std::collections::HashMap;

use chisel::Backend;
use chisel::surface::field::{NativeSamples, SampleVisitor, Scalar};
use chisel::surface::{IsoSpec, McOptions, Surface, marching_cubes};
use chisel::volume::{Volume, VolumeData};

// ---------------------------------------------------------------- oracle

/// Voxel-side topology of an inside mask on a grid whose border samples are
/// all outside (as the padded grid of `close_border`).
///
/// The case table's convention makes inside 6-connected and outside
/// 26-connected, so the surface is the boundary of a neighbourhood of the
/// lattice cubical complex K6(A) of each inside component A (cells: voxels,
/// 6-adjacent pairs, full 2×2 squares, full 2×2×2 cubes), and equally of the
/// union K26(B) of closed unit cubes of each outside component B. A shell
/// separates one A from one B; shells form a tree (Jordan–Brouwer), and the
/// shells around a node have Euler characteristics summing to 2χ(K) (minus 2
/// for the unbounded B, whose realisation also has the grid's outer face).
/// Peeling leaves gives every shell's χ.
struct VoxelTopology {
    /// Component of each inside sample (6-connected), or u32::MAX.
    inside_label: Vec<u32>,
    /// Component of each outside sample (26-connected), or u32::MAX.
    outside_label: Vec<u32>,
    /// χ per shell (A, B).
    shells: HashMap<(u32, u32), i64>,
    /// Whether B is the parent of A (A's outer shell) for each shell.
    outer: HashMap<(u32, u32), bool>,
}

fn label(mask: &[bool], dims: [usize; 3], want: bool, full: bool) -> (Vec<u32>, u32) {
    let [nx, ny, nz] = dims;
    let mut lab = vec![u32::MAX; mask.len()];
    let mut n = 0;
    let mut stack = Vec::new();
    let offsets: Vec<[i64; 3]> = (0..27)
        .map(|i| [i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1])
        .filter(|o| {
            let k = o.iter().filter(|&&v| v != 0).count();
            k > 0 && (full || k == 1)
        })
        .collect();
    for s in 0..mask.len() {
        if mask[s] != want || lab[s] != u32::MAX {
            continue;
        }
        lab[s] = n;
        stack.push(s);
        while let Some(p) = stack.pop() {
            let c = [p % nx, (p / nx) % ny, p / (nx * ny)];
            for o in &offsets {
                let q = [c[0] as i64 + o[0], c[1] as i64 + o[1], c[2] as i64 + o[2]];
                if q[0] < 0 || q[1] < 0 || q[2] < 0 {
                    continue;
                }
                let q = [q[0] as usize, q[1] as usize, q[2] as usize];
                if q[0] >= nx || q[1] >= ny || q[2] >= nz {
                    continue;
                }
                let qi = q[0] + nx * (q[1] + ny * q[2]);
                if mask[qi] == want && lab[qi] == u32::MAX {
                    lab[qi] = n;
                    stack.push(qi);
                }
            }
        }
        n += 1;
    }
    (lab, n)
}

impl VoxelTopology {
    fn new(mask: &[bool], dims: [usize; 3]) -> Self {
        let [nx, ny, nz] = dims;
        let idx = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        assert!(!mask[0], "grid border must be outside");
        let (lab6, n_a) = label(mask, dims, true, false);
        let (lab26, n_b) = label(mask, dims, false, true);
        // χ(K6(A)): voxels − edges + squares − cubes, all inside.
        let mut chi_a = vec![0i64; n_a as usize];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let p = idx(x, y, z);
                    if !mask[p] {
                        continue;
                    }
                    let a = lab6[p] as usize;
                    chi_a[a] += 1;
                    let at = |dx: usize, dy: usize, dz: usize| {
                        x + dx < nx
                            && y + dy < ny
                            && z + dz < nz
                            && mask[idx(x + dx, y + dy, z + dz)]
                    };
                    let e = [at(1, 0, 0), at(0, 1, 0), at(0, 0, 1)];
                    chi_a[a] -= e.iter().filter(|&&b| b).count() as i64;
                    let sq = [
                        e[0] && e[1] && at(1, 1, 0),
                        e[1] && e[2] && at(0, 1, 1),
                        e[0] && e[2] && at(1, 0, 1),
                    ];
                    chi_a[a] += sq.iter().filter(|&&b| b).count() as i64;
                    if sq.iter().all(|&b| b) && at(1, 1, 1) {
                        chi_a[a] -= 1;
                    }
                }
            }
        }
        // χ(K26(B)): dual vertices/edges/faces touched by B, minus B's cubes.
        // A dual k-cell is a window of voxels (2×2×2, 2×2, 1×2) over
        // positions −1..n per axis; windows never touch two components.
        let mut chi_b = vec![0i64; n_b as usize];
        let get = |x: i64, y: i64, z: i64| -> Option<u32> {
            if x < 0 || y < 0 || z < 0 || x >= nx as i64 || y >= ny as i64 || z >= nz as i64 {
                return None;
            }
            let l = lab26[idx(x as usize, y as usize, z as usize)];
            (l != u32::MAX).then_some(l)
        };
        for z in -1..nz as i64 {
            for y in -1..ny as i64 {
                for x in -1..nx as i64 {
                    // Window with extents w (0 or 1 per axis) at (x, y, z).
                    let window = |w: [i64; 3]| -> Option<u32> {
                        for dz in 0..=w[2] {
                            for dy in 0..=w[1] {
                                for dx in 0..=w[0] {
                                    if let Some(l) = get(x + dx, y + dy, z + dz) {
                                        return Some(l);
                                    }
                                }
                            }
                        }
                        None
                    };
                    if let Some(l) = window([1, 1, 1]) {
                        chi_b[l as usize] += 1;
                    }
                    for w in [[0, 1, 1], [1, 0, 1], [1, 1, 0]] {
                        if let Some(l) = window(w) {
                            chi_b[l as usize] -= 1;
                        }
                    }
                    for w in [[1, 0, 0], [0, 1, 0], [0, 0, 1]] {
                        if let Some(l) = window(w) {
                            chi_b[l as usize] += 1;
                        }
                    }
                    if let Some(l) = get(x, y, z) {
                        chi_b[l as usize] -= 1;
                    }
                }
            }
        }
        let b_outer = lab26[0];
        // Shell graph.
        let mut adj: HashMap<(u32, u32), ()> = HashMap::new();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let p = idx(x, y, z);
                    for (dx, dy, dz) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        if x + dx >= nx || y + dy >= ny || z + dz >= nz {
                            continue;
                        }
                        let q = idx(x + dx, y + dy, z + dz);
                        if mask[p] != mask[q] {
                            let (i, o) = if mask[p] { (p, q) } else { (q, p) };
                            adj.insert((lab6[i], lab26[o]), ());
                        }
                    }
                }
            }
        }
        // Node residuals: inside nodes 0..n_a, outside nodes n_a.. .
        let n_nodes = (n_a + n_b) as usize;
        let mut residual: Vec<i64> = chi_a.iter().map(|c| 2 * c).collect();
        residual.extend(
            chi_b
                .iter()
                .enumerate()
                .map(|(b, c)| 2 * c - if b as u32 == b_outer { 2 } else { 0 }),
        );
        let mut nbrs: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
        for &(a, b) in adj.keys() {
            nbrs[a as usize].push(n_a as usize + b as usize);
            nbrs[n_a as usize + b as usize].push(a as usize);
        }
        assert_eq!(adj.len() + 1, n_nodes, "shell graph must be a tree");
        // Root at the outer component; parents by BFS.
        let root = n_a as usize + b_outer as usize;
        let mut parent = vec![usize::MAX; n_nodes];
        let mut order = vec![root];
        parent[root] = root;
        let mut i = 0;
        while i < order.len() {
            let u = order[i];
            i += 1;
            for &v in &nbrs[u] {
                if parent[v] == usize::MAX {
                    parent[v] = u;
                    order.push(v);
                }
            }
        }
        assert_eq!(order.len(), n_nodes, "shell graph must be connected");
        let mut shells = HashMap::new();
        let mut outer = HashMap::new();
        for &u in order.iter().rev().filter(|&&u| u != root) {
            let p = parent[u];
            let chi = residual[u];
            residual[p] -= chi;
            let key = if u < n_a as usize {
                ((u) as u32, (p - n_a as usize) as u32)
            } else {
                (p as u32, (u - n_a as usize) as u32)
            };
            shells.insert(key, chi);
            outer.insert(key, u < n_a as usize);
        }
        assert_eq!(residual[root], 0, "residual at the root");
        VoxelTopology {
            inside_label: lab6,
            outside_label: lab26,
            shells,
            outer,
        }
    }
}

// ---------------------------------------------------------------- checks

/// Every directed edge once, every edge in both directions (closed,
/// oriented 2-manifold); returns V − E + F per group from the mesh itself.
fn check_closed_oriented(s: &Surface) -> Vec<i64> {
    let m = &s.mesh;
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, tri) in m.triangles.iter().enumerate() {
        assert!(
            tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2],
            "triangle {t} repeats a vertex"
        );
        // Differences and products of these f32 coordinates are exact in
        // f64, so a zero here is a zero area.
        let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
        assert_ne!(
            (b - a).cross(c - a),
            glam::DVec3::ZERO,
            "triangle {t} has zero area: {a} {b} {c}"
        );
        for k in 0..3 {
            let e = (tri[k], tri[(k + 1) % 3]);
            assert!(
                directed.insert(e, t as u32).is_none(),
                "directed edge {e:?} used twice"
            );
        }
    }
    for &(a, b) in directed.keys() {
        assert!(
            directed.contains_key(&(b, a)),
            "edge ({a},{b}) used once: not watertight/oriented"
        );
    }
    let n = s.groups.len();
    let mut v = vec![0i64; n];
    let mut e = vec![0i64; n];
    let mut f = vec![0i64; n];
    let mut vg = vec![u32::MAX; m.positions.len()];
    for (tri, &g) in m.triangles.iter().zip(&s.triangle_groups) {
        f[g as usize] += 1;
        for &i in tri {
            assert!(
                vg[i as usize] == u32::MAX || vg[i as usize] == g,
                "vertex in two groups"
            );
            vg[i as usize] = g;
        }
    }
    assert!(vg.iter().all(|&g| g != u32::MAX), "unused vertex");
    for &g in &vg {
        v[g as usize] += 1;
    }
    for (&(a, b), &t) in &directed {
        if a < b {
            e[s.triangle_groups[t as usize] as usize] += 1;
        }
    }
    (0..n).map(|g| v[g] - e[g] + f[g]).collect()
}

/// No two triangles meet beyond their shared vertices and edges (exact).
fn check_embedded(s: &Surface) {
    let hits = chisel::mesh::self_intersections(&s.mesh);
    assert!(
        hits.degenerate.is_empty(),
        "zero-area triangles {:?}",
        hits.degenerate
    );
    let show: Vec<_> = hits
        .pairs
        .iter()
        .take(4)
        .map(|&[i, j]| {
            let t = |k: u32| s.mesh.triangles[k as usize].map(|v| s.mesh.positions[v as usize]);
            (t(i), t(j))
        })
        .collect();
    assert!(
        hits.pairs.is_empty(),
        "{} crossing triangle pairs, e.g. {show:?}",
        hits.pairs.len()
    );
}

/// Vertices are welded: one vertex per grid edge.
fn check_welded(s: &Surface) {
    let mut seen = std::collections::HashSet::new();
    for &k in &s.vertex_edges {
        assert!(seen.insert(k), "grid edge {k} has two vertices");
    }
}

/// The inside mask the surface was extracted from, padded with outside.
fn padded_mask(vol: &Volume, iso: IsoSpec) -> (Vec<bool>, [usize; 3]) {
    let [nx, ny, nz] = vol.dims;
    let dims = [nx + 2, ny + 2, nz + 2];
    let mut mask = vec![false; dims.iter().product()];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let v = vol.data.get_f64(vol.index(x, y, z));
                let inside = match iso {
                    IsoSpec::Level(l) => (v as f32) >= l,
                    IsoSpec::Label(l) => v == l,
                };
                mask[(x + 1) + dims[0] * ((y + 1) + dims[1] * (z + 1))] = inside;
            }
        }
    }
    (mask, dims)
}

/// Full check of a closed surface against the voxel oracle.
fn check_topology(vol: &Volume, iso: IsoSpec, s: &Surface) {
    check_welded(s);
    let chi = check_closed_oriented(s);
    check_embedded(s);
    let (mask, dims) = padded_mask(vol, iso);
    assert_eq!(s.grid.dims, dims);
    let topo = VoxelTopology::new(&mask, dims);
    assert_eq!(
        s.groups.len(),
        topo.shells.len(),
        "group count vs voxel shells"
    );
    let mut shell_of_group = vec![None; s.groups.len()];
    let mut vg = vec![u32::MAX; s.mesh.positions.len()];
    for (tri, &g) in s.mesh.triangles.iter().zip(&s.triangle_groups) {
        for &i in tri {
            vg[i as usize] = g;
        }
    }
    for (v, &key) in s.vertex_edges.iter().enumerate() {
        let (p, axis) = ((key / 3) as usize, (key % 3) as usize);
        let step = [1, dims[0], dims[0] * dims[1]][axis];
        let (i, o) = if mask[p] {
            (p, p + step)
        } else {
            (p + step, p)
        };
        assert!(mask[i] && !mask[o], "vertex {v} not on a crossing edge");
        let shell = (topo.inside_label[i], topo.outside_label[o]);
        let g = vg[v] as usize;
        match shell_of_group[g] {
            None => shell_of_group[g] = Some(shell),
            Some(s0) => assert_eq!(s0, shell, "group {g} spans two voxel shells"),
        }
    }
    let mut used = std::collections::HashSet::new();
    for (g, group) in s.groups.iter().enumerate() {
        let shell = shell_of_group[g].expect("group has vertices");
        assert!(used.insert(shell), "two groups on shell {shell:?}");
        let want = topo.shells[&shell];
        assert_eq!(chi[g], want, "group {g}: mesh χ vs voxel χ");
        assert_eq!(group.euler, want, "group {g}: reported χ vs voxel χ");
        assert_eq!(group.genus, Some((2 - want) / 2));
        assert_eq!(group.boundary_edges, 0);
        assert!(group.area > 0.0, "group {g} has no area");
        if topo.outer[&shell] {
            assert!(
                group.volume > 0.0,
                "group {g}: outer shell, volume {}",
                group.volume
            );
        } else {
            assert!(
                group.volume < 0.0,
                "group {g}: cavity shell, volume {}",
                group.volume
            );
        }
    }
}

// ---------------------------------------------------------------- fixtures

fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed.max(1);
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// Seeded random u8 volume with values 0..=255, smoothed a little so that
/// all case configurations and real components/cavities occur.
fn random_volume(seed: u64, dims: [usize; 3]) -> Volume {
    let mut next = xorshift(seed);
    let data: Vec<u8> = (0..dims.iter().product::<usize>())
        .map(|_| (next() % 256) as u8)
        .collect();
    Volume::new(dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap()
}

/// Signed distance-like phantom: `f(p) = r − |p − c|` sampled as f32.
fn ball(n: usize, r: f64, spacing: [f64; 3], origin: [f64; 3]) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let d = ((x as f64 - c).powi(2) + (y as f64 - c).powi(2) + (z as f64 - c).powi(2))
                    .sqrt();
                data.push((r - d) as f32);
            }
        }
    }
    Volume::new([n; 3], spacing, origin, VolumeData::F32(data)).unwrap()
}

/// Solid torus phantom around the z axis: `f = r − dist(p, circle R)`.
fn torus(n: usize, big_r: f64, r: f64) -> Volume {
    let c = (n as f64 - 1.0) / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (dx, dy, dz) = (x as f64 - c, y as f64 - c, z as f64 - c);
                let q = ((dx * dx + dy * dy).sqrt() - big_r).hypot(dz);
                data.push((r - q) as f32);
            }
        }
    }
    Volume::new([n; 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap()
}

const CLOSE: McOptions = McOptions { close_border: true };

// ---------------------------------------------------------------- tests

#[test]
fn random_volumes_match_voxel_topology() {
    for seed in 1..=12u64 {
        let vol = random_volume(seed, [9, 8, 7]);
        // Integer levels put samples exactly on the level.
        for level in [60.0f32, 60.5, 128.0, 128.5, 200.5] {
            let iso = IsoSpec::Level(level);
            let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
            check_topology(&vol, iso, &s);
        }
    }
}

#[test]
fn every_single_cell_case_is_closed_and_matches_voxel_topology() {
    for case in 1..255u32 {
        let data: Vec<u8> = (0..8)
            .map(|c| if case >> c & 1 == 1 { 200 } else { 10 })
            .collect();
        let vol = Volume::new([2, 2, 2], [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
        // Between the samples, and exactly at the inside ones.
        for level in [100.0, 200.0] {
            let iso = IsoSpec::Level(level);
            let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
            check_topology(&vol, iso, &s);
        }
    }
}

#[test]
fn ball_is_one_outward_sphere_with_the_right_volume() {
    let vol = ball(40, 15.0, [1.0; 3], [0.0; 3]);
    let s = marching_cubes(&vol, IsoSpec::Level(0.0), &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, IsoSpec::Level(0.0), &s);
    assert_eq!(s.groups.len(), 1);
    let g = &s.groups[0];
    assert_eq!(g.genus, Some(0));
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 15f64.powi(3);
    assert!(
        (g.volume - exact).abs() / exact < 0.01,
        "volume {} vs {exact}",
        g.volume
    );
    let area = 4.0 * std::f64::consts::PI * 15f64.powi(2);
    assert!(
        (g.area - area).abs() / area < 0.02,
        "area {} vs {area}",
        g.area
    );
}

#[test]
fn torus_has_genus_one() {
    let vol = torus(48, 14.0, 5.0);
    let s = marching_cubes(&vol, IsoSpec::Level(0.0), &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, IsoSpec::Level(0.0), &s);
    assert_eq!(s.groups.len(), 1);
    assert_eq!(s.groups[0].genus, Some(1));
}

#[test]
fn spacing_and_origin_are_honoured() {
    let a = ball(24, 8.0, [1.0; 3], [0.0; 3]);
    let b = ball(24, 8.0, [0.5, 2.0, 3.0], [10.0, -5.0, 7.0]);
    let sa = marching_cubes(&a, IsoSpec::Level(0.0), &McOptions::default(), Backend::Cpu).unwrap();
    let sb = marching_cubes(&b, IsoSpec::Level(0.0), &McOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(sa.mesh.triangles, sb.mesh.triangles);
    for (p, q) in sa.mesh.positions.iter().zip(&sb.mesh.positions) {
        let want = glam::Vec3::new(10.0 + 0.5 * p.x, -5.0 + 2.0 * p.y, 7.0 + 3.0 * p.z);
        assert!((want - *q).abs().max_element() < 1e-4, "{want} vs {q}");
    }
    let ratio = sb.groups[0].volume / sa.groups[0].volume;
    assert!(
        (ratio - 3.0).abs() < 1e-6,
        "volume scales with the voxel size: {ratio}"
    );
}

#[test]
fn open_border_surfaces_report_their_boundary() {
    // A slab filling the volume in x and y: open without closing, closed with.
    let dims = [6, 5, 6];
    let data: Vec<u8> = (0..180)
        .map(|i| {
            if (i / 30) % 6 >= 2 && (i / 30) % 6 <= 3 {
                9
            } else {
                0
            }
        })
        .collect();
    let vol = Volume::new(dims, [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    let open = marching_cubes(
        &vol,
        IsoSpec::Level(5.0),
        &McOptions::default(),
        Backend::Cpu,
    )
    .unwrap();
    assert_eq!(open.groups.len(), 2, "two open sheets");
    for g in &open.groups {
        assert_eq!(g.genus, None);
        assert_eq!(g.boundary_edges, 2 * (4 + 5), "boundary around a 5×4 sheet");
        assert_eq!(g.euler, 1, "a disk");
    }
    let closed = marching_cubes(&vol, IsoSpec::Level(5.0), &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, IsoSpec::Level(5.0), &closed);
    assert_eq!(closed.groups.len(), 1);
}

#[test]
fn border_closing_holds_for_levels_beyond_f32_integers() {
    // At |level| ≥ 2²⁴, level − 1 rounds back to the level: the padding
    // must still be outside, or the corners would join the solid.
    for level in [1.0e9f32, -3.0e8] {
        let inside = if level > 0.0 {
            2.0 * level
        } else {
            0.5 * level
        };
        let vol = Volume::new(
            [3; 3],
            [1.0; 3],
            [0.0; 3],
            VolumeData::F32(vec![inside; 27]),
        )
        .unwrap();
        let iso = IsoSpec::Level(level);
        let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
        check_topology(&vol, iso, &s);
        assert_eq!(s.groups.len(), 1);
        assert_eq!(s.groups[0].euler, 2);
    }
}

#[test]
fn labels_and_non_finite_samples() {
    let data = vec![0u8, 3, 3, 0, 7, 3, 3, 3];
    let vol = Volume::new([2, 2, 2], [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    let iso = IsoSpec::Label(3.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
    let bad = Volume::new(
        [2, 1, 1],
        [1.0; 3],
        [0.0; 3],
        VolumeData::F32(vec![0.0, f32::NAN]),
    )
    .unwrap();
    let err = marching_cubes(&bad, IsoSpec::Level(0.5), &CLOSE, Backend::Cpu).unwrap_err();
    assert!(err.to_string().contains("not finite"), "{err}");
    assert!(marching_cubes(&vol, IsoSpec::Level(f32::NAN), &CLOSE, Backend::Cpu).is_err());
}

#[test]
fn forest_covers_every_triangle_once_with_true_boxes() {
    let vol = random_volume(7, [12, 11, 10]);
    let s = marching_cubes(&vol, IsoSpec::Level(128.0), &CLOSE, Backend::Cpu).unwrap();
    let f = &s.forest;
    assert_eq!(f.groups.len(), s.groups.len());
    let mut seen = vec![false; s.mesh.triangles.len()];
    for (g, node) in f.groups.iter().enumerate() {
        let mut leaf = f.rows[f.layers[node.layers.start as usize].rows.start as usize]
            .cells
            .start;
        let mut chained = 0;
        while leaf != u32::MAX {
            chained += 1;
            leaf = f.cells[leaf as usize].next;
        }
        let mut n_cells = 0;
        for l in node.layers.range() {
            let layer = &f.layers[l];
            assert!(
                node.bbox.min.cmple(layer.bbox.min).all()
                    && layer.bbox.max.cmple(node.bbox.max).all()
            );
            for r in layer.rows.range() {
                let row = &f.rows[r];
                for c in row.cells.range() {
                    n_cells += 1;
                    let cell = &f.cells[c];
                    for &t in &f.triangles[cell.triangles.range()] {
                        assert_eq!(s.triangle_groups[t as usize], g as u32);
                        // Leaves are blocks of LEAF_BLOCK³ marching-cubes cells.
                        let key = s.triangle_cells[t as usize] as usize;
                        let b = chisel::surface::LEAF_BLOCK;
                        let g = s.grid.dims.map(|d| d - 1);
                        let key = {
                            let (x, y, z) = (key % g[0], (key / g[0]) % g[1], key / (g[0] * g[1]));
                            x / b + f.cell_dims[0] * (y / b + f.cell_dims[1] * (z / b))
                        };
                        let cd = f.cell_dims;
                        assert_eq!(
                            (key % cd[0], (key / cd[0]) % cd[1], key / (cd[0] * cd[1])),
                            (cell.x as usize, row.y as usize, layer.z as usize)
                        );
                        assert!(!seen[t as usize]);
                        seen[t as usize] = true;
                        for &v in &s.mesh.triangles[t as usize] {
                            let p = s.mesh.positions[v as usize];
                            assert!(cell.bbox.min.cmple(p).all() && p.cmple(cell.bbox.max).all());
                        }
                    }
                }
            }
        }
        assert_eq!(chained, n_cells, "leaf chain of group {g}");
        assert_eq!(f.group_triangles(g).len() as u32, s.groups[g].triangles);
    }
    assert!(seen.iter().all(|&b| b));
}

// ---------------------------------------------------------------- real data

fn headsq() -> Option<Volume> {
    common::real_volume("headsq/quarter.nhdr")
}

#[test]
fn headsq_skin_500_is_closed_and_matches_voxel_topology() {
    let Some(vol) = headsq() else { return };
    let iso = IsoSpec::Level(500.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
    eprintln!(
        "headsq 500: {} triangles, {} groups",
        s.mesh.triangles.len(),
        s.groups.len()
    );
}

#[test]
fn headsq_bone_1150_is_closed_and_matches_voxel_topology() {
    let Some(vol) = headsq() else { return };
    let iso = IsoSpec::Level(1150.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
    eprintln!(
        "headsq 1150: {} triangles, {} groups",
        s.mesh.triangles.len(),
        s.groups.len()
    );
}

#[test]
fn head_mr_volume_is_closed_and_matches_voxel_topology() {
    let Some(vol) = common::real_volume("HeadMRVolume.mhd") else {
        return;
    };
    let iso = IsoSpec::Level(42.0);
    let s = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
    check_topology(&vol, iso, &s);
}

/// Frog labels: the oracle runs on the label's bounding box (plus one
/// outside sample per side), which has the same topology as the full grid.
#[test]
fn frog_labels_are_closed_and_match_voxel_topology() {
    let Some(vol) = common::real_volume("froggy/frogtissue.mhd") else {
        return;
    };
    for label in [2.0, 4.0, 14.0, 24.0] {
        let crop = crop_to_label(&vol, label);
        let iso = IsoSpec::Label(label);
        let s = marching_cubes(&crop, iso, &CLOSE, Backend::Cpu).unwrap();
        check_topology(&crop, iso, &s);
        let full = marching_cubes(&vol, iso, &CLOSE, Backend::Cpu).unwrap();
        assert_eq!(
            full.mesh.triangles.len(),
            s.mesh.triangles.len(),
            "label {label}"
        );
        assert_eq!(full.groups.len(), s.groups.len(), "label {label}");
        let euler = |s: &Surface| {
            let mut e: Vec<i64> = s.groups.iter().map(|g| g.euler).collect();
            e.sort_unstable();
            e
        };
        assert_eq!(euler(&full), euler(&s), "label {label}");
        check_closed_oriented(&full);
        eprintln!(
            "frog label {label}: {} triangles, {} groups",
            s.mesh.triangles.len(),
            s.groups.len()
        );
    }
}

fn crop_to_label(vol: &Volume, label: f64) -> Volume {
    let [nx, ny, nz] = vol.dims;
    let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if vol.data.get_f64(vol.index(x, y, z)) == label {
                    for (a, c) in [x, y, z].into_iter().enumerate() {
                        lo[a] = lo[a].min(c);
                        hi[a] = hi[a].max(c);
                    }
                }
            }
        }
    }
    let dims = [hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1];
    let mut data = Vec::with_capacity(dims.iter().product());
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                data.push(vol.data.get_f64(vol.index(x, y, z)) as u8);
            }
        }
    }
    let origin = [0, 1, 2].map(|a| vol.origin[a] + vol.spacing[a] * lo[a] as f64);
    Volume::new(dims, vol.spacing, origin, VolumeData::U8(data)).unwrap()
}

/// Every sample of the padded grid read through `NativeSamples` (x
/// fastest, then y, then z).
struct AllSamples([usize; 3]);

impl SampleVisitor for AllSamples {
    type Output = Vec<f32>;

    fn visit<T: Scalar>(self, samples: NativeSamples<'_, '_, T>) -> Vec<f32> {
        let [nx, ny, nz] = self.0;
        let mut out = Vec::with_capacity(nx * ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    out.push(samples.sample(x, y, z));
                }
            }
        }
        out
    }
}

/// The CPU reads inside flags as bit rows in the native type and samples
/// only at crossings (`Field::sample`, and `NativeSamples` with the type
/// known at compile time); all must equal the `f32` layers the GPU uploads
/// (`Field::layer`), for every sample type, with and without padding, at
/// levels between, on and beyond the integer values, and for labels.
#[test]
fn field_rows_and_samples_match_layers() {
    let dims = [70, 5, 4];
    let n: usize = dims.iter().product();
    let mut next = xorshift(77);
    let raw: Vec<i64> = (0..n).map(|_| (next() % 9) as i64 - 4).collect();
    let volumes = [
        VolumeData::U8(raw.iter().map(|&v| (v + 4) as u8).collect()),
        VolumeData::I8(raw.iter().map(|&v| v as i8).collect()),
        VolumeData::U16(raw.iter().map(|&v| (v + 4) as u16 * 1000).collect()),
        VolumeData::I16(raw.iter().map(|&v| v as i16 * 1000).collect()),
        VolumeData::U32(raw.iter().map(|&v| (v + 4) as u32 * 100_000_007).collect()),
        VolumeData::I32(raw.iter().map(|&v| v as i32 * 100_000_007).collect()),
        VolumeData::F32(raw.iter().map(|&v| v as f32 * 0.3).collect()),
        VolumeData::F64(raw.iter().map(|&v| v as f64 * 0.3 + 1e-9).collect()),
    ];
    let isos = [
        IsoSpec::Level(0.0),
        IsoSpec::Level(0.5),
        IsoSpec::Level(-1.0),
        IsoSpec::Level(2.0),
        IsoSpec::Level(1000.0),
        IsoSpec::Level(-3999.5),
        IsoSpec::Level(1e6),
        IsoSpec::Level(1e30),
        IsoSpec::Level(-1e30),
        IsoSpec::Level(300_000_021.0),
        IsoSpec::Level(0.6),
        IsoSpec::Label(0.0),
        IsoSpec::Label(2.0),
        IsoSpec::Label(-2.0),
        IsoSpec::Label(2000.0),
        IsoSpec::Label(0.5),
        IsoSpec::Label(1e12),
    ];
    let mut checked_inside = 0usize;
    for data in volumes {
        let vol = Volume::new(dims, [1.0; 3], [0.0; 3], data).unwrap();
        for iso in isos {
            for close in [false, true] {
                let field = chisel::surface::Field::new(&vol, iso, close).unwrap();
                let [nx, ny, nz] = field.dims;
                let native = field.visit_samples(AllSamples(field.dims));
                let mut layer = vec![0f32; nx * ny];
                let mut row = vec![0u64; field.row_words()];
                for z in 0..nz {
                    field.layer(z, &mut layer);
                    for y in 0..ny {
                        field.inside_row(y, z, &mut row);
                        for x in 0..field.row_words() * 64 {
                            let bit = row[x / 64] >> (x % 64) & 1 == 1;
                            let want = x < nx && layer[x + nx * y] >= field.level;
                            assert_eq!(
                                bit,
                                want,
                                "{:?} {iso:?} close {close}: inside ({x}, {y}, {z})",
                                vol.data.scalar_type()
                            );
                            checked_inside += usize::from(want);
                            if x < nx {
                                let want = layer[x + nx * y].to_bits();
                                let s = field.sample(x, y, z);
                                let n = native[x + nx * (y + ny * z)];
                                for (got, what) in [(s, "sample"), (n, "native sample")] {
                                    assert_eq!(
                                        got.to_bits(),
                                        want,
                                        "{:?} {iso:?} close {close}: {what} ({x}, {y}, {z})",
                                        vol.data.scalar_type()
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        checked_inside > 0,
        "no inside sample: the test proves nothing"
    );
}

/// The CPU walk splits the grid into chunks by thread count; stitching must
/// make the output independent of it (vertex ids, triangle order, groups).
#[test]
fn cpu_output_does_not_depend_on_thread_count() {
    let vol = random_volume(5, [37, 29, 41]);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| marching_cubes(&vol, IsoSpec::Level(127.5), &CLOSE, Backend::Cpu))
            .unwrap()
    };
    let one = run(1);
    assert!(one.groups.len() > 1, "want several groups");
    for threads in [2, 3, 7] {
        let many = run(threads);
        assert_eq!(one.mesh.triangles, many.mesh.triangles, "{threads} threads");
        assert_eq!(one.mesh.positions, many.mesh.positions, "{threads} threads");
        assert_eq!(one.vertex_edges, many.vertex_edges, "{threads} threads");
        assert_eq!(one.triangle_cells, many.triangle_cells, "{threads} threads");
        assert_eq!(
            one.triangle_groups, many.triangle_groups,
            "{threads} threads"
        );
        assert_eq!(one.groups, many.groups, "{threads} threads");
        assert_eq!(one.forest, many.forest, "{threads} threads");
    }
}
