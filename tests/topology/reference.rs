//! A brute-force reference on random soups and perforated spheres.

use std::collections::{HashMap, HashSet, VecDeque};

use chisel::TriMesh;
use chisel::mesh::{Orientation, Topology, orient_consistently};

use crate::common::{icosphere, random_mesh, xorshift};

/// Brute-force figures of a triangle soup, written independently of the
/// library: hash maps, per-vertex BFS, BFS components.
struct Reference {
    edges: usize,
    boundary: usize,
    manifold: usize,
    nonmanifold: usize,
    nonmanifold_vertices: usize,
    consistent: bool,
    component_triangles: Vec<usize>,
    euler: i64,
}

fn reference(m: &TriMesh) -> Reference {
    let live: Vec<[u32; 3]> = m
        .triangles
        .iter()
        .copied()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut uses: HashMap<(u32, u32), Vec<(usize, u32)>> = HashMap::new();
    for (i, t) in live.iter().enumerate() {
        for k in 0..3 {
            uses.entry(key(t[k], t[(k + 1) % 3]))
                .or_default()
                .push((i, t[k]));
        }
    }
    let count = |f: &dyn Fn(usize) -> bool| uses.values().filter(|u| f(u.len())).count();
    let consistent = uses
        .values()
        .filter(|u| u.len() == 2)
        .all(|u| u[0].1 != u[1].1);
    let mut nm = HashSet::new();
    for (&(a, b), u) in &uses {
        if u.len() > 2 {
            nm.insert(a);
            nm.insert(b);
        }
    }
    let vertices: HashSet<u32> = live.iter().flatten().copied().collect();
    for &v in &vertices {
        let around: Vec<usize> = (0..live.len()).filter(|&i| live[i].contains(&v)).collect();
        let mut seen = vec![false; around.len()];
        let mut fans = 0;
        for s in 0..around.len() {
            if seen[s] {
                continue;
            }
            fans += 1;
            seen[s] = true;
            let mut q = VecDeque::from([s]);
            while let Some(x) = q.pop_front() {
                for &w in live[around[x]].iter().filter(|&&w| w != v) {
                    let u = &uses[&key(v, w)];
                    if u.len() != 2 {
                        continue;
                    }
                    for &(t, _) in u {
                        let y = around.iter().position(|&a| a == t).unwrap();
                        if !seen[y] {
                            seen[y] = true;
                            q.push_back(y);
                        }
                    }
                }
            }
        }
        if fans > 1 {
            nm.insert(v);
        }
    }
    let mut adj: HashMap<u32, Vec<u32>> = HashMap::new();
    for t in &live {
        for k in 0..3 {
            adj.entry(t[k]).or_default().push(t[(k + 1) % 3]);
            adj.entry(t[(k + 1) % 3]).or_default().push(t[k]);
        }
    }
    let mut comp: HashMap<u32, usize> = HashMap::new();
    let mut n_comp = 0;
    let mut sorted: Vec<u32> = vertices.iter().copied().collect();
    sorted.sort_unstable();
    for &s in &sorted {
        if comp.contains_key(&s) {
            continue;
        }
        comp.insert(s, n_comp);
        let mut q = VecDeque::from([s]);
        while let Some(x) = q.pop_front() {
            for &y in &adj[&x] {
                if let std::collections::hash_map::Entry::Vacant(e) = comp.entry(y) {
                    e.insert(n_comp);
                    q.push_back(y);
                }
            }
        }
        n_comp += 1;
    }
    let mut component_triangles = vec![0; n_comp];
    for t in &live {
        component_triangles[comp[&t[0]]] += 1;
    }
    component_triangles.sort_unstable_by(|a, b| b.cmp(a));
    Reference {
        edges: uses.len(),
        boundary: count(&|n| n == 1),
        manifold: count(&|n| n == 2),
        nonmanifold: count(&|n| n > 2),
        nonmanifold_vertices: nm.len(),
        consistent,
        component_triangles,
        euler: vertices.len() as i64 - uses.len() as i64 + live.len() as i64,
    }
}

fn assert_matches_reference(m: &TriMesh, what: &str) {
    let topo = Topology::of(m);
    let r = reference(m);
    assert_eq!(topo.edges, r.edges, "{what}");
    assert_eq!(topo.boundary_edges, r.boundary, "{what}");
    assert_eq!(topo.manifold_edges, r.manifold, "{what}");
    assert_eq!(topo.nonmanifold_edges, r.nonmanifold, "{what}");
    assert_eq!(topo.nonmanifold_vertices, r.nonmanifold_vertices, "{what}");
    assert_eq!(topo.consistently_oriented, r.consistent, "{what}");
    assert_eq!(topo.euler, r.euler, "{what}");
    let tris: Vec<usize> = topo.components.iter().map(|c| c.triangles).collect();
    assert_eq!(tris, r.component_triangles, "{what}");
    let walked: usize = topo
        .boundary_loops
        .iter()
        .chain(&topo.open_boundary_chains)
        .sum();
    assert_eq!(
        walked, topo.boundary_edges,
        "{what}: every boundary edge walked once"
    );
    let per_comp: usize = topo.components.iter().map(|c| c.edges).sum();
    assert_eq!(per_comp, topo.edges, "{what}");
}

#[test]
fn random_soups_match_brute_force() {
    for seed in 1..=12 {
        for (nv, nt) in [(12, 8), (30, 40), (40, 200)] {
            assert_matches_reference(
                &random_mesh(seed, nv, nt),
                &format!("seed {seed} {nv}/{nt}"),
            );
        }
    }
}

#[test]
fn perforated_spheres_match_brute_force_and_directed_loops() {
    for seed in 1..=8u64 {
        let mut next = xorshift(seed * 7919);
        let mut m = icosphere(2);
        m.triangles.retain(|_| !next().is_multiple_of(5));
        assert_matches_reference(&m, &format!("perforated {seed}"));
        let topo = Topology::of(&m);
        // Without pinch vertices, boundary loops are the cycles of the
        // successor map of the boundary half-edges.
        if topo.nonmanifold_vertices == 0 {
            let mut directed: HashSet<(u32, u32)> = HashSet::new();
            for t in &m.triangles {
                for k in 0..3 {
                    directed.insert((t[k], t[(k + 1) % 3]));
                }
            }
            let next_of: HashMap<u32, u32> = directed
                .iter()
                .filter(|&&(a, b)| !directed.contains(&(b, a)))
                .map(|&(a, b)| (a, b))
                .collect();
            let mut seen = HashSet::new();
            let mut loops = Vec::new();
            let mut starts: Vec<u32> = next_of.keys().copied().collect();
            starts.sort_unstable();
            for s in starts {
                let mut len = 0;
                let mut v = s;
                while seen.insert(v) {
                    v = next_of[&v];
                    len += 1;
                }
                if len > 0 {
                    loops.push(len);
                }
            }
            loops.sort_unstable_by(|a, b| b.cmp(a));
            assert_eq!(topo.boundary_loops, loops, "seed {seed}");
        }
        // Random flips are undone by orient_consistently, patch by patch.
        let mut scrambled = m.clone();
        for t in scrambled.triangles.iter_mut() {
            if next().is_multiple_of(7) {
                t.swap(1, 2);
            }
        }
        orient_consistently(&mut scrambled).unwrap();
        let after = Topology::of(&scrambled);
        assert!(after.consistently_oriented, "seed {seed}");
        assert_eq!(after.orientation, Orientation::Outward, "seed {seed}");
    }
}
