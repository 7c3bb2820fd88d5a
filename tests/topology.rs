//! Mesh topology, orientation detection and re-winding: synthetic families
//! with known figures, brute-force references on random soups, and the real
//! meshes' figures from `../shared/data/README.md`.

mod common;

use std::collections::{HashMap, HashSet, VecDeque};
use std::f32::consts::TAU;
use std::f64::consts::{PI, TAU as TAU64};

use chisel::TriMesh;
use chisel::mesh::{Orientation, Topology, orient_consistently, orient_outward};
use common::{cube, icosphere, random_mesh, real_mesh, tetra};
use glam::Vec3;

/// Torus with major radius 2, minor radius 0.5, `n × m` quads, outward.
fn torus(n: u32, m: u32) -> TriMesh {
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (u, v) = (TAU * i as f32 / n as f32, TAU * j as f32 / m as f32);
            let ring = 2.0 + 0.5 * v.cos();
            p.push(Vec3::new(ring * u.cos(), ring * u.sin(), 0.5 * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut t = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.extend([[a, b, c], [a, c, d]]);
        }
    }
    TriMesh::new(p, t).unwrap()
}

/// Flat disk in z = 0: centre 0 and a ring of `n` vertices, counter-clockwise
/// seen from +z.
fn disk(n: u32) -> TriMesh {
    let mut p = vec![Vec3::ZERO];
    p.extend((0..n).map(|i| {
        let a = TAU * i as f32 / n as f32;
        Vec3::new(a.cos(), a.sin(), 0.0)
    }));
    let t = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
    TriMesh::new(p, t).unwrap()
}

/// Möbius strip of `n` quads (non-orientable).
fn moebius(n: u32) -> TriMesh {
    let mut p = Vec::new();
    for i in 0..n {
        let u = TAU * i as f32 / n as f32;
        for w in [-0.3f32, 0.3] {
            let r = 1.0 + w * (u / 2.0).cos();
            p.push(Vec3::new(r * u.cos(), r * u.sin(), w * (u / 2.0).sin()));
        }
    }
    let mut t = Vec::new();
    for i in 0..n {
        let (a, d) = (2 * i, 2 * i + 1);
        // The last quad closes the strip with a half twist.
        let (b, c) = if i + 1 < n {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        t.extend([[a, b, c], [a, c, d]]);
    }
    TriMesh::new(p, t).unwrap()
}

/// Upper cap of an icosphere: the triangles whose centroid has z > 0.3.
fn cap() -> TriMesh {
    let mut m = icosphere(2);
    let p = m.positions.clone();
    m.triangles
        .retain(|t| t.iter().map(|&v| p[v as usize].z).sum::<f32>() / 3.0 > 0.3);
    m
}

/// `a` and `b` as one mesh (indices of `b` shifted).
fn union(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let off = a.positions.len() as u32;
    let mut p = a.positions.clone();
    p.extend(&b.positions);
    let mut t = a.triangles.clone();
    t.extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
    TriMesh::new(p, t).unwrap()
}

fn translated(m: &TriMesh, d: Vec3) -> TriMesh {
    let mut m = m.clone();
    m.positions.iter_mut().for_each(|p| *p += d);
    m
}

fn flipped(m: &TriMesh) -> TriMesh {
    let mut m = m.clone();
    m.flip_winding();
    m
}

/// Checks the figures every closed, consistently wound genus-`g` shell has.
fn assert_closed_shell(m: &TriMesh, genus: i64, orientation: Orientation) -> Topology {
    let topo = Topology::of(m);
    assert_eq!(topo.boundary_edges, 0);
    assert_eq!(topo.nonmanifold_edges, 0);
    assert_eq!(topo.nonmanifold_vertices, 0);
    assert_eq!(topo.edges, 3 * m.triangles.len() / 2);
    assert!(topo.boundary_loops.is_empty());
    assert!(topo.closed && topo.consistently_oriented && topo.is_manifold());
    assert_eq!(topo.components.len(), 1);
    let c = &topo.components[0];
    assert!(c.closed && c.manifold && c.orientable);
    assert_eq!(c.genus, Some(genus));
    assert_eq!(topo.euler, 2 - 2 * genus);
    assert_eq!(c.euler, topo.euler);
    assert_eq!(topo.orientation, orientation);
    assert_eq!(c.orientation, orientation);
    topo
}

#[test]
fn platonic_and_sphere_shells_are_genus_zero_and_outward() {
    let t = assert_closed_shell(&tetra(), 0, Orientation::Outward);
    assert!(
        (t.signed_volume - 8.0 / 3.0).abs() < 1e-6,
        "{}",
        t.signed_volume
    );
    let c = assert_closed_shell(&cube(), 0, Orientation::Outward);
    assert!((c.signed_volume - 1.0).abs() < 1e-9);
    assert!((c.area - 6.0).abs() < 1e-9);
    assert_eq!(c.bounds.unwrap().max, [1.0, 1.0, 1.0]);
    let s = assert_closed_shell(&icosphere(3), 0, Orientation::Outward);
    let ball = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(s.signed_volume < ball && s.signed_volume > 0.97 * ball);
}

#[test]
fn flipped_shells_are_inward_and_orient_outward_restores_them() {
    for m in [tetra(), cube(), icosphere(2), torus(16, 8)] {
        let genus = Topology::of(&m).components[0].genus.unwrap();
        let mut f = flipped(&m);
        let topo = assert_closed_shell(&f, genus, Orientation::Inward);
        assert!(topo.signed_volume < 0.0);
        assert_eq!(orient_outward(&mut f), 1);
        assert_eq!(f, m, "re-flipping restores the original winding exactly");
        assert_eq!(orient_outward(&mut f), 0);
    }
}

#[test]
fn torus_has_genus_one() {
    let t = assert_closed_shell(&torus(24, 12), 1, Orientation::Outward);
    assert_eq!(t.euler, 0);
    // Pappus with polygons: a 12-gon cross-section of area (12/2π)·sin(2π/12)·πr²
    // swept along a 24-gon of perimeter (24/2π)·sin(2π/24)·2πR.
    let polygon = |n: f64| n / TAU64 * (TAU64 / n).sin();
    let pappus = polygon(12.0) * PI * 0.25 * polygon(24.0) * TAU64 * 2.0;
    assert!(
        (t.signed_volume / pappus - 1.0).abs() < 2e-3,
        "{} vs {pappus}",
        t.signed_volume
    );
}

#[test]
fn flat_disk_is_open_with_one_loop_and_undetermined() {
    let topo = Topology::of(&disk(12));
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (24, 12, 12)
    );
    assert_eq!(topo.boundary_loops, vec![12]);
    assert!(topo.open_boundary_chains.is_empty());
    assert_eq!(topo.euler, 1);
    assert!(!topo.closed && topo.consistently_oriented && topo.is_manifold());
    let c = &topo.components[0];
    assert_eq!((c.closed, c.genus, c.boundary_edges), (false, None, 12));
    assert_eq!(topo.orientation, Orientation::Undetermined);
    assert_eq!(
        Topology::of(&flipped(&disk(12))).orientation,
        Orientation::Undetermined
    );
    let mut d = disk(12);
    assert_eq!(orient_outward(&mut d), 0);
}

#[test]
fn open_cap_orientation_follows_its_curvature() {
    let cap = cap();
    let topo = Topology::of(&cap);
    assert!(topo.used_vertices < topo.vertices);
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.boundary_loops.len(), 1);
    assert_eq!(topo.euler, 1);
    assert_eq!(topo.orientation, Orientation::Outward);
    let mut inward = flipped(&cap);
    assert_eq!(Topology::of(&inward).orientation, Orientation::Inward);
    assert_eq!(orient_outward(&mut inward), 1);
    assert_eq!(inward, cap);
}

#[test]
fn disjoint_cubes_are_two_components() {
    let small = translated(&flipped(&tetra()), Vec3::new(10.0, 0.0, 0.0));
    let m = union(
        &small,
        &union(&cube(), &translated(&cube(), Vec3::splat(3.0))),
    );
    let topo = Topology::of(&m);
    assert_eq!(topo.components.len(), 3);
    let tris: Vec<usize> = topo.components.iter().map(|c| c.triangles).collect();
    assert_eq!(tris, vec![12, 12, 4], "by size descending");
    assert_eq!(
        topo.components[0].first_triangle, 4,
        "ties by first triangle"
    );
    assert_eq!(topo.components[1].first_triangle, 16);
    assert_eq!(topo.euler, 6);
    assert!(topo.components.iter().all(|c| c.genus == Some(0)));
    assert_eq!(topo.components[2].orientation, Orientation::Inward);
    assert_eq!(topo.orientation, Orientation::Mixed, "components disagree");
    let mut fixed = m.clone();
    assert_eq!(orient_outward(&mut fixed), 1);
    let after = Topology::of(&fixed);
    assert_eq!(after.orientation, Orientation::Outward);
    assert!((after.signed_volume - 2.0 - 8.0 / 3.0).abs() < 1e-6);
}

#[test]
fn three_triangles_on_one_edge() {
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::new(0.5, 1.0, 0.0),
        Vec3::new(0.5, -1.0, 0.0),
        Vec3::new(0.5, 0.0, 1.0),
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let topo = Topology::of(&m);
    assert_eq!(topo.edges, 7);
    assert_eq!(
        (
            topo.boundary_edges,
            topo.manifold_edges,
            topo.nonmanifold_edges
        ),
        (6, 0, 1)
    );
    assert_eq!(topo.nonmanifold_vertices, 2);
    assert!(topo.boundary_loops.is_empty());
    assert_eq!(topo.open_boundary_chains, vec![2, 2, 2]);
    assert!(!topo.is_manifold());
    let c = &topo.components[0];
    assert!(!c.manifold && c.genus.is_none());
    assert_eq!(c.nonmanifold_edges, 1);
}

#[test]
fn bowtie_vertex_is_nonmanifold_and_splits_boundary_loops() {
    let p = vec![
        Vec3::ZERO,
        Vec3::new(1.0, -0.5, 0.0),
        Vec3::new(1.0, 0.5, 0.0),
        Vec3::new(-1.0, 0.5, 0.0),
        Vec3::new(-1.0, -0.5, 0.0),
    ];
    let m = TriMesh::new(p, vec![[0, 1, 2], [0, 3, 4]]).unwrap();
    let topo = Topology::of(&m);
    assert_eq!(topo.nonmanifold_vertices, 1);
    assert_eq!(topo.nonmanifold_edges, 0);
    assert_eq!(topo.components.len(), 1, "vertex-sharing triangles connect");
    assert_eq!(topo.boundary_loops, vec![3, 3]);
    assert_eq!(topo.euler, 1);
    // Two closed cubes touching at one corner: a pinch, so no genus.
    let mut touching = translated(&cube(), Vec3::ONE);
    touching.positions.remove(0);
    let n = cube().positions.len() as u32;
    touching.triangles = touching
        .triangles
        .iter()
        .map(|t| t.map(|v| if v == 0 { 7 } else { v - 1 + n }))
        .collect();
    let mut both = cube();
    both.positions.extend(touching.positions);
    both.triangles.extend(touching.triangles);
    both.validate().unwrap();
    let topo = Topology::of(&both);
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.nonmanifold_vertices, 1);
    assert!(topo.closed);
    assert_eq!(topo.components[0].genus, None);
    assert_eq!(topo.euler, 3);
}

/// Strip of `n` quads in the plane, every triangle counter-clockwise.
fn strip(n: u32) -> TriMesh {
    let p = (0..=n)
        .flat_map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32, 1.0, 0.0)])
        .collect();
    let t = (0..n)
        .flat_map(|i| {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            [[a, b, c], [a, c, d]]
        })
        .collect();
    TriMesh::new(p, t).unwrap()
}

#[test]
fn inconsistent_strip_is_mixed_and_orient_consistently_fixes_the_minority() {
    let good = strip(5);
    let mut m = good.clone();
    m.triangles[3].swap(1, 2);
    m.triangles[7].swap(0, 1);
    let topo = Topology::of(&m);
    assert!(!topo.consistently_oriented);
    assert_eq!(topo.orientation, Orientation::Mixed);
    assert_eq!(
        topo.boundary_loops,
        vec![12],
        "loops do not need consistent winding"
    );
    assert_eq!(
        orient_outward(&mut m.clone()),
        0,
        "mixed components are left alone"
    );
    assert_eq!(orient_consistently(&mut m).unwrap(), 2);
    let after = Topology::of(&m);
    assert!(after.consistently_oriented);
    let normal = |m: &TriMesh, t: usize| {
        let [a, b, c] = m.triangles[t].map(|v| m.positions[v as usize]);
        (b - a).cross(c - a).z
    };
    assert!(
        (0..10).all(|t| normal(&m, t) > 0.0),
        "majority winding kept"
    );
    // Majority rule: with most triangles flipped the patch is wound the other way.
    let mut mostly = flipped(&good);
    mostly.triangles[0].swap(1, 2);
    assert_eq!(orient_consistently(&mut mostly).unwrap(), 1);
    assert_eq!(mostly, flipped(&good));
}

#[test]
fn moebius_strip_is_not_orientable() {
    let m = moebius(12);
    let topo = Topology::of(&m);
    assert!(!topo.consistently_oriented);
    assert_eq!(
        topo.boundary_loops,
        vec![24],
        "one boundary curve, twice around"
    );
    assert_eq!(topo.euler, 0);
    assert!(!topo.components[0].orientable);
    let mut copy = m.clone();
    let err = orient_consistently(&mut copy).unwrap_err();
    assert!(err.to_string().contains("non-orientable"), "{err}");
    assert_eq!(copy, m, "left unchanged on error");
}

#[test]
fn degenerate_triangles_are_counted_and_collapsed_ones_ignored() {
    let mut m = cube();
    m.positions.push(Vec3::new(2.0, 0.0, 0.0));
    m.positions.push(Vec3::new(3.0, 0.0, 0.0));
    m.positions.push(Vec3::new(4.0, 0.0, 0.0));
    m.triangles.push([8, 9, 10]); // collinear: zero area
    m.triangles.push([0, 0, 1]); // collapsed
    m.triangles.push([5, 5, 5]); // collapsed
    let topo = Topology::of(&m);
    assert_eq!(topo.triangles, 15);
    assert_eq!(topo.degenerate_triangles, 3);
    assert_eq!(topo.collapsed_triangles, 2);
    assert_eq!(topo.used_vertices, 11);
    assert_eq!(topo.edges, 18 + 3);
    assert_eq!(topo.components.len(), 2);
    assert_eq!(topo.components[1].triangles, 1);
    assert_eq!(topo.components[1].orientation, Orientation::Undetermined);
    assert_eq!(topo.orientation, Orientation::Outward);
    assert_eq!(topo.euler, 2 + 1);
}

#[test]
fn empty_mesh() {
    let topo = Topology::of(&TriMesh::default());
    assert_eq!((topo.edges, topo.euler, topo.components.len()), (0, 0, 0));
    assert!(!topo.closed && topo.bounds.is_none());
    assert_eq!(topo.orientation, Orientation::Undetermined);
}

#[test]
fn json_field_names() {
    let v = serde_json::to_value(Topology::of(&cube())).unwrap();
    assert_eq!(v["orientation"], "outward");
    assert_eq!(v["boundary_loops"], serde_json::json!([]));
    assert_eq!(v["components"][0]["genus"], 0);
    assert_eq!(v["bounds"]["min"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(v["used_vertices"], 8);
}

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

/// xorshift for the perforation tests.
fn rng(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

#[test]
fn perforated_spheres_match_brute_force_and_directed_loops() {
    for seed in 1..=8u64 {
        let mut next = rng(seed * 7919);
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

#[test]
fn fran_cut_is_an_inward_disk() {
    let Some(m) = real_mesh("fran_cut.vtk") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (2205, 2205, 4224)
    );
    assert_eq!(topo.degenerate_triangles, 0);
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (6428, 184, 6244)
    );
    assert_eq!((topo.nonmanifold_edges, topo.nonmanifold_vertices), (0, 0));
    assert_eq!(topo.components.len(), 1);
    assert_eq!(topo.boundary_loops, vec![184]);
    assert_eq!(topo.euler, 1);
    assert!(topo.consistently_oriented && !topo.closed);
    assert_eq!(topo.orientation, Orientation::Inward);
    assert!((topo.area - 0.033760).abs() < 1e-5, "{}", topo.area);
    let mut out = m.clone();
    assert_eq!(orient_outward(&mut out), 1);
    assert_eq!(Topology::of(&out).orientation, Orientation::Outward);
}

#[test]
fn bunny_is_inward_genus_zero_with_five_holes() {
    let Some(m) = real_mesh("bunny.ply") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (35947, 34834, 69451)
    );
    assert_eq!(topo.degenerate_triangles, 0);
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (104288, 223, 104065)
    );
    assert_eq!((topo.nonmanifold_edges, topo.nonmanifold_vertices), (0, 0));
    assert_eq!(topo.boundary_loops, vec![80, 42, 40, 39, 22]);
    assert_eq!(topo.euler, -3);
    assert_eq!(topo.components.len(), 1);
    assert!(topo.consistently_oriented);
    assert_eq!(topo.orientation, Orientation::Inward);
    assert!((topo.area - 0.057129).abs() < 1e-5, "{}", topo.area);
    assert!(topo.signed_volume < -5e-4, "{}", topo.signed_volume);
}

#[test]
fn footbones_are_26_outward_genus_zero_shells() {
    let Some(m) = real_mesh("fsu/footbones.ply") else {
        return;
    };
    let topo = Topology::of(&m);
    assert_eq!(
        (topo.vertices, topo.used_vertices, topo.triangles),
        (2154, 2154, 4204)
    );
    assert_eq!(
        (topo.edges, topo.boundary_edges, topo.manifold_edges),
        (6306, 0, 6306)
    );
    assert_eq!(topo.nonmanifold_vertices, 0);
    assert_eq!(topo.euler, 52);
    assert!(topo.closed && topo.consistently_oriented);
    let tris: Vec<usize> = topo.components.iter().map(|c| c.triangles).collect();
    assert_eq!(
        tris,
        vec![
            598, 586, 392, 360, 228, 212, 154, 146, 146, 146, 134, 134, 134, 126, 124, 74, 66, 60,
            60, 60, 48, 46, 46, 46, 46, 32
        ]
    );
    assert!(
        topo.components
            .iter()
            .all(|c| c.closed && c.genus == Some(0))
    );
    assert!(
        topo.components
            .iter()
            .all(|c| c.orientation == Orientation::Outward)
    );
    assert_eq!(topo.orientation, Orientation::Outward);
    assert!(
        (topo.signed_volume - 18.5289).abs() < 1e-3,
        "{}",
        topo.signed_volume
    );
    let mut f = flipped(&m);
    assert_eq!(Topology::of(&f).orientation, Orientation::Inward);
    assert_eq!(orient_outward(&mut f), 26);
    assert_eq!(Topology::of(&f).orientation, Orientation::Outward);
    assert_eq!(f, m);
}
