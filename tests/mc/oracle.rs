//! The independent voxel-topology oracle (cubical complexes) and the checks
//! every surface must pass: closed, oriented, embedded, welded, and the
//! oracle's group counts and Euler characteristics.

use std::collections::HashMap;

use chisel::mc::{IsoSpec, Surface};
use chisel::volume::Volume;

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
pub(crate) fn check_closed_oriented(s: &Surface) -> Vec<i64> {
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
pub(crate) fn check_embedded(s: &Surface) {
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
pub(crate) fn check_welded(s: &Surface) {
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
pub(crate) fn check_topology(vol: &Volume, iso: IsoSpec, s: &Surface) {
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
