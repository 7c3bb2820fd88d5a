//! The DMS room's evaluation lattice (SPEC §2.5): the seed's Table 3
//! counts, shared edge and vertex points (no cracks, no duplicates), the
//! input's orientation kept, n = 2 giving back the input, and fran_cut.

mod common;

use std::collections::HashMap;

use chisel::dms::{lattice, lattice_counts};
use chisel::{Error, Position};

/// A `cols × rows` grid of vertices as a disk of `2(cols − 1)(rows − 1)`
/// counter-clockwise triangles.
fn grid(cols: u32, rows: u32) -> Vec<[u32; 3]> {
    let v = |c: u32, r: u32| r * cols + c;
    let mut t = Vec::new();
    for r in 0..rows - 1 {
        for c in 0..cols - 1 {
            t.push([v(c, r), v(c + 1, r), v(c + 1, r + 1)]);
            t.push([v(c, r), v(c + 1, r + 1), v(c, r + 1)]);
        }
    }
    t
}

/// Each directed edge once, each undirected edge at most twice: a
/// consistently oriented manifold; returns (edges, boundary edges).
fn manifold_edges(triangles: &[[u32; 3]]) -> (usize, usize) {
    let mut uses: HashMap<(u32, u32), i32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            assert_ne!(a, b, "degenerate output triangle {t:?}");
            *uses.entry((a.min(b), a.max(b))).or_default() += if a < b { 2 } else { -2 };
        }
    }
    // A twice-used edge is walked once each way (sum 0); a boundary edge once.
    let boundary = uses.values().filter(|&&s| s.abs() == 2).count();
    assert!(
        uses.values().all(|&s| s == 0 || s.abs() == 2),
        "an edge is used twice in one direction or more than twice"
    );
    (uses.len(), boundary)
}

#[test]
fn table_3_counts() {
    // (p, t) of the seed's data sets; all are disks, so E = p + t − 1.
    // Table 3 as printed, with its three misprinted cells corrected
    // (docs/design/dms.md): C at n = 7 has its columns swapped, D at n = 3
    // prints C's n = 5 triangle count, D at n = 7 is an extrapolation.
    type Row = (&'static str, u64, u64, [(u64, u64); 3]);
    let table: [Row; 4] = [
        (
            "A",
            552,
            1012,
            [(2115, 4048), (8277, 16192), (18487, 36432)],
        ),
        (
            "B",
            1157,
            2273,
            [(4586, 9092), (18263, 36368), (41032, 81828)],
        ),
        (
            "C",
            1502,
            2976,
            [(5979, 11904), (23861, 47616), (53647, 107136)],
        ),
        (
            "D",
            8641,
            17001,
            [(34282, 68004), (136567, 272016), (306856, 612036)],
        ),
    ];
    for (name, p, t, cells) in table {
        for (n, want) in [3, 5, 7].into_iter().zip(cells) {
            assert_eq!(
                lattice_counts(p, p + t - 1, t, n),
                want,
                "{name} at n = {n}"
            );
        }
    }
    // A is a 24 × 23 grid: the lattice itself has those counts.
    let a = grid(24, 23);
    assert_eq!(a.len(), 1012);
    for (n, want) in [(3, (2115, 4048)), (5, (8277, 16192)), (7, (18487, 36432))] {
        let l = lattice(&a, 552, n).unwrap();
        assert_eq!(
            (l.points.len() as u64, l.triangles.len() as u64),
            want,
            "A at n = {n}"
        );
    }
}

#[test]
fn lattices_are_crack_free_oriented_disks() {
    let input = grid(5, 4);
    let (e_in, b_in) = manifold_edges(&input);
    for n in 2..=9u32 {
        let l = lattice(&input, 20, n).unwrap();
        let (e, b) = manifold_edges(&l.triangles);
        let v = l.points.len();
        // Still a disk (Euler characteristic 1), every boundary edge split in n − 1.
        assert_eq!(v as i64 - e as i64 + l.triangles.len() as i64, 1, "n = {n}");
        assert_eq!(b, b_in * (n as usize - 1), "n = {n}");
        assert_eq!(
            (v as u64, l.triangles.len() as u64),
            lattice_counts(20, e_in as u64, input.len() as u64, n as u64)
        );
        // Every point is used, and each point's (triangle, i, j) lies in its triangle.
        let mut used = vec![false; v];
        l.triangles
            .iter()
            .flatten()
            .for_each(|&p| used[p as usize] = true);
        assert!(used.iter().all(|&u| u), "n = {n}: an unused point");
        assert!(l.points.iter().all(|p| p.i + p.j < n));
    }
    // n = 2 gives back the input, vertex points renumbered by first use.
    let l = lattice(&input, 20, 2).unwrap();
    let back: Vec<[u32; 3]> = input
        .iter()
        .map(|t| t.map(|v| l.vertex_points[v as usize]))
        .collect();
    assert_eq!(l.triangles, back);
}

#[test]
fn shared_points_carry_one_position() {
    // The two triangles of a shared edge name the same lattice points at
    // the same parameter position: evaluate u from each point's own
    // triangle and compare where the ids meet.
    let input = grid(4, 4);
    let uv: Vec<[f64; 2]> = (0..16)
        .map(|k| [(k % 4) as f64, (k / 4) as f64 * 1.5])
        .collect();
    let n = 6;
    let l = lattice(&input, 16, n).unwrap();
    let at = |t: u32, i: u32, j: u32| {
        let [a, b, c] = input[t as usize].map(|v| uv[v as usize]);
        let (s, r) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
        [
            a[0] + s * (b[0] - a[0]) + r * (c[0] - a[0]),
            a[1] + s * (b[1] - a[1]) + r * (c[1] - a[1]),
        ]
    };
    let pos: Vec<[f64; 2]> = l.points.iter().map(|p| at(p.triangle, p.i, p.j)).collect();
    // Every output triangle has positive area in the (counter-clockwise) grid.
    for t in &l.triangles {
        let [a, b, c] = t.map(|p| pos[p as usize]);
        let d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        assert!(d > 0.0, "{t:?}: area {d}");
    }
    // No two points at one position.
    let mut keys: Vec<(i64, i64)> = pos
        .iter()
        .map(|p| ((p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), pos.len(), "duplicated points");
}

#[test]
fn bad_input_is_refused() {
    let t = grid(3, 3);
    for n in [0, 1, 65_537] {
        assert!(matches!(
            lattice(&t, 9, n),
            Err(Error::InvalidParameter { ref name, .. }) if name == "n"
        ));
    }
    assert!(matches!(
        lattice(&t, 8, 3),
        Err(Error::InvalidData {
            at: Position::Item {
                kind: "triangle",
                ..
            },
            ..
        })
    ));
    assert!(matches!(
        lattice(&[[0, 1, 1]], 3, 3),
        Err(Error::InvalidData {
            at: Position::Item {
                kind: "triangle",
                index: 0
            },
            ..
        })
    ));
}

#[test]
fn fran_cut_at_n_5() {
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let l = lattice(&mesh.triangles, mesh.n_vertices(), 5).unwrap();
    // p 2205, t 4224, E 6428 (docs/design/dms.md).
    assert_eq!((l.points.len(), l.triangles.len()), (34_161, 67_584));
    manifold_edges(&l.triangles);
}

mod param {
    use chisel::dms::param::det;
    use chisel::dms::{Projection, parametrise};
    use chisel::{Error, Refusal, TriMesh};
    use glam::{DVec2, Quat, Vec3};

    use super::{common, grid};

    fn mesh(positions: Vec<Vec3>, cols: u32, rows: u32) -> TriMesh {
        TriMesh::new(positions, grid(cols, rows)).unwrap()
    }

    fn all_positive(uv: &[DVec2], m: &TriMesh) -> bool {
        m.triangles.iter().all(|&t| det(uv, t) > 0.0)
    }

    #[test]
    fn planar_is_an_isometry_of_a_flat_mesh() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.7, -1.2, 2.1);
        let (cols, rows) = (7, 5);
        let pts: Vec<Vec3> = (0..cols * rows)
            .map(|k| q * Vec3::new((k % cols) as f32 * 1.5, (k / cols) as f32, 0.0) + Vec3::ONE)
            .collect();
        let m = mesh(pts.clone(), cols, rows);
        let p = parametrise(&m, &Projection::Planar).unwrap();
        assert!(all_positive(&p.uv, &m) && p.repaired.is_empty());
        for (a, b) in [(0, 34), (3, 17), (8, 30), (6, 28)] {
            let d3 = (pts[a] - pts[b]).length() as f64;
            let d2 = p.uv[a].distance(p.uv[b]);
            assert!((d3 - d2).abs() < 1e-5, "{a}–{b}: {d3} vs {d2}");
        }
    }

    #[test]
    fn cylinder_unrolls_about_the_fitted_axis() {
        // A grid on a cylinder of radius 2 about x = 1, z = −3, facing −x.
        let (cols, rows) = (21, 6);
        let angle = |c: u32| (std::f32::consts::PI * (0.5 + c as f32 / 20.0 * 1.1)).rem_euclid(6.3);
        let pts: Vec<Vec3> = (0..cols * rows)
            .map(|k| {
                let (c, r) = (k % cols, k / cols);
                let a = angle(c);
                Vec3::new(1.0 + 2.0 * a.sin(), r as f32 * 0.4, -3.0 + 2.0 * a.cos())
            })
            .collect();
        let m = mesh(pts, cols, rows);
        let p = parametrise(&m, &Projection::Cylinder).unwrap();
        let chisel::dms::param::ParamMap::Cylinder { centre, radius, .. } = p.map else {
            panic!("a cylinder map: {:?}", p.map)
        };
        // Projecting the vertices again gives their parameter points.
        for (v, q) in m.positions.iter().enumerate() {
            let u = p.project(*q).unwrap();
            assert!(
                u.distance(p.uv[v]) < 1e-12,
                "vertex {v}: {u} vs {}",
                p.uv[v]
            );
        }
        assert!(centre.distance(DVec2::new(1.0, -3.0)) < 1e-5, "{centre}");
        assert!((radius - 2.0).abs() < 1e-5, "{radius}");
        assert!(all_positive(&p.uv, &m) && p.repaired.is_empty());
        // Arc lengths along a row: R · Δα.
        let step = 2.0 * std::f64::consts::PI * 1.1 / 20.0;
        let d = p.uv[1].distance(p.uv[0]);
        assert!((d - step).abs() < 1e-5, "{d} vs {step}");
        // The seam lies opposite the mean direction: the domain is centred.
        let mid = (p.uv[0].x + p.uv[20].x) / 2.0;
        assert!(mid.abs() < 1e-5, "{mid}");
    }

    #[test]
    fn isolated_flips_are_repaired_and_clusters_refused() {
        let (cols, rows) = (6, 6);
        let flat: Vec<DVec2> = (0..cols * rows)
            .map(|k| DVec2::new((k % cols) as f64, (k / cols) as f64))
            .collect();
        let m = mesh(vec![Vec3::ZERO; (cols * rows) as usize], cols, rows);
        // One interior vertex pushed past its neighbour: its star folds.
        let mut uv = flat.clone();
        uv[14] = DVec2::new(3.6, 2.0);
        let bad: Vec<u32> = (0..m.triangles.len() as u32)
            .filter(|&t| det(&uv, m.triangles[t as usize]) <= 0.0)
            .collect();
        assert!(!bad.is_empty());
        let p = parametrise(&m, &Projection::Given(uv)).unwrap();
        assert_eq!(p.repaired, bad);
        assert!(all_positive(&p.uv, &m));
        // A whole column collapsed (boundary vertices included): refused with its ids.
        let mut uv = flat;
        for r in 0..rows {
            uv[(r * cols + 2) as usize].x = 1.0;
        }
        match parametrise(&m, &Projection::Given(uv)) {
            Err(Error::Refused(Refusal::FoldedParameters { triangles })) => {
                assert_eq!(triangles.len(), 2 * (rows as usize - 1), "{triangles:?}")
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn an_overlapping_domain_is_refused() {
        // A strip wound one and a half times round a spiral: every triangle
        // positive, the boundary crossing itself.
        let (cols, rows) = (40, 2);
        let uv: Vec<DVec2> = (0..cols * rows)
            .map(|k| {
                let (c, r) = ((k % cols) as f64, (k / cols) as f64);
                let a = c / (cols - 1) as f64 * 3.0 * std::f64::consts::PI;
                // 0.31 wider per turn than a lap, 0.5 wide: the laps overlap.
                let radius = 3.0 + 0.05 * a - 0.5 * r;
                DVec2::new(radius * a.cos(), radius * a.sin())
            })
            .collect();
        let m = mesh(vec![Vec3::ZERO; (cols * rows) as usize], cols, rows);
        let err = parametrise(&m, &Projection::Given(uv)).unwrap_err();
        assert!(
            matches!(err, Error::Refused(Refusal::OverlappingParameters { .. })),
            "{err}"
        );
    }

    #[test]
    fn fran_cut_cylinder_and_planar() {
        let Some(m) = common::real_mesh("fran_cut.vtk") else {
            return;
        };
        // About the fitted axis every triangle comes out negative, so the
        // domain is mirrored, and none needs repair (docs/design/dms.md §1).
        let p = parametrise(&m, &Projection::Cylinder).unwrap();
        assert!(p.mirrored && p.repaired.is_empty());
        assert!(all_positive(&p.uv, &m));
        // The planar projection folds the sides of the face (83 triangles,
        // 53 still after the repair of isolated ones): refused, with ids.
        match parametrise(&m, &Projection::Planar) {
            Err(Error::Refused(Refusal::FoldedParameters { triangles })) => {
                assert_eq!(triangles.len(), 53)
            }
            other => panic!("expected a refusal, got {:?}", other.map(|p| p.repaired)),
        }
    }
}

mod knots {
    use chisel::dms::knots::{RADIUS_FRACTION, quality, scored_triples};
    use chisel::dms::{Projection, knot_clouds, parametrise};
    use chisel::{Error, Refusal};
    use glam::DVec2;

    use super::knots_fixture::jittered_domain;
    use super::{common, grid};

    #[test]
    fn the_37_scored_triples() {
        let t = scored_triples();
        assert_eq!(t.len(), 37);
        // The ten DMS triangles [r_i, s_j, t_k], i + j + k ≤ 2, are the signed ones.
        let signed: Vec<[usize; 3]> = t.iter().filter(|(_, s)| *s).map(|(k, _)| *k).collect();
        assert_eq!(signed.len(), 10);
        assert!(
            signed
                .iter()
                .all(|k| k.map(|x| x / 3) == [0, 1, 2]
                    && k.iter().map(|x| x % 3).sum::<usize>() <= 2)
        );
        assert!(
            (quality(DVec2::ZERO, DVec2::X, DVec2::new(0.5, 3f64.sqrt() / 2.0)) - 1.0).abs()
                < 1e-12
        );
        assert!(quality(DVec2::ZERO, DVec2::new(0.5, 3f64.sqrt() / 2.0), DVec2::X) < 0.0);
    }

    #[test]
    fn knots_keep_their_regions_and_every_triple_independent() {
        let (cols, rows) = (7, 6);
        let (uv, _) = jittered_domain(cols, rows);
        let tris = grid(cols, rows);
        let k = knot_clouds(&uv, &tris).unwrap();
        assert!(k.min_quality > 1e-3, "min quality {}", k.min_quality);
        let boundary = |v: usize| {
            let (c, r) = (v as u32 % cols, v as u32 / cols);
            c == 0 || r == 0 || c == cols - 1 || r == rows - 1
        };
        for (v, cloud) in k.knots.iter().enumerate() {
            assert_eq!(cloud[0], uv[v]);
            let star: Vec<[DVec2; 3]> = (tris.iter())
                .filter(|t| t.contains(&(v as u32)))
                .map(|t| t.map(|w| uv[w as usize]))
                .collect();
            let nearest = (star.iter().flatten())
                .filter(|&&p| p != uv[v])
                .map(|p| p.distance(uv[v]))
                .fold(f64::INFINITY, f64::min);
            for &q in &cloud[1..] {
                assert!((q.distance(uv[v]) - RADIUS_FRACTION * nearest).abs() < 1e-12);
                let inside = star.iter().any(|[a, b, c]| {
                    (*b - *a).perp_dot(q - *a) > 0.0
                        && (*c - *b).perp_dot(q - *b) > 0.0
                        && (*a - *c).perp_dot(q - *c) > 0.0
                });
                // Interior vertices inside their star, boundary ones outside the domain.
                assert_eq!(inside, !boundary(v), "vertex {v}");
            }
        }
    }

    #[test]
    fn a_star_too_thin_for_the_candidates_is_refused() {
        // A fan round vertex 0 from `from`° to 365°: the outer wedge
        // (5°, `from`°). At 10° the 15° step has no candidate there, its
        // halvings do (Θ/8: 5.6°, 7.5°, 9.4°); at 5.1° not even Θ/64 ≈
        // 0.23° fits two.
        let fan = |from: f64| {
            let n = 24;
            let mut uv = vec![DVec2::ZERO];
            for k in 0..=n {
                let a = (from + (365.0 - from) * k as f64 / n as f64).to_radians();
                uv.push(DVec2::new(a.cos(), a.sin()));
            }
            let tris: Vec<[u32; 3]> = (1..=n as u32).map(|k| [0, k, k + 1]).collect();
            knot_clouds(&uv, &tris)
        };
        let k = fan(10.0).unwrap();
        for knot in &k.knots[0][1..] {
            let a = knot.y.atan2(knot.x).to_degrees();
            assert!(a > 5.0 && a < 10.0, "{a}°");
        }
        assert!(matches!(
            fan(5.1),
            Err(Error::Refused(Refusal::NoKnotPosition { vertex: 0 }))
        ));
    }

    #[test]
    fn fran_cut_knots() {
        let Some(m) = common::real_mesh("fran_cut.vtk") else {
            return;
        };
        let p = parametrise(&m, &Projection::Cylinder).unwrap();
        let k = knot_clouds(&p.uv, &m.triangles).unwrap();
        eprintln!(
            "fran_cut: smallest knot-triple quality {:.4}",
            k.min_quality
        );
        assert!(k.min_quality > 0.0, "{}", k.min_quality);
    }
}

mod oracle {
    use chisel::dms::knot_clouds;
    use chisel::dms::knots::BETAS;
    use chisel::dms::oracle::{bsplines, simplex_spline};
    use glam::DVec2;

    use super::knots_fixture::{jittered_domain, points_of};

    /// Σ over every triangle of the six B-splines at `u`, and each value.
    fn basis(u: DVec2, clouds: &[[[DVec2; 3]; 3]]) -> Vec<[f64; 6]> {
        clouds.iter().map(|&c| bsplines(u, c)).collect()
    }

    #[test]
    fn partition_of_unity_and_positivity_up_to_the_border() {
        let (uv, tris) = jittered_domain(7, 6);
        let k = knot_clouds(&uv, &tris).unwrap();
        let clouds: Vec<[[DVec2; 3]; 3]> = tris
            .iter()
            .map(|t| t.map(|v| k.knots[v as usize]))
            .collect();
        for u in points_of(&uv, &tris) {
            let b = basis(u, &clouds);
            let sum: f64 = b.iter().flatten().sum();
            assert!((sum - 1.0).abs() < 1e-12, "Σ N = {sum} at {u}");
            // N ≥ 0; the recursion's signed λ leave rounding of the
            // partition's order (−6e-15 seen at a boundary vertex).
            let low = b.iter().flatten().copied().fold(f64::INFINITY, f64::min);
            assert!(low >= -1e-12, "negative N {low:e} at {u}");
        }
    }

    #[test]
    fn quadratics_are_reproduced_from_their_blossoms() {
        let (uv, tris) = jittered_domain(6, 5);
        let k = knot_clouds(&uv, &tris).unwrap();
        // P(u) = uᵀAu + b·u + c and its blossom p(x, y) = xᵀAy + b·(x + y)/2 + c.
        let (a, b, c) = ([0.7, -0.4, 1.3], DVec2::new(-2.0, 0.5), 3.0);
        let blossom = |x: DVec2, y: DVec2| {
            a[0] * x.x * y.x
                + a[1] * (x.x * y.y + x.y * y.x)
                + a[2] * x.y * y.y
                + b.dot(x + y) / 2.0
                + c
        };
        for u in points_of(&uv, &tris) {
            let mut f = 0.0;
            for t in &tris {
                let clouds = t.map(|v| k.knots[v as usize]);
                let n = bsplines(u, clouds);
                for (s, beta) in BETAS.iter().enumerate() {
                    // The control point of N_β: the blossom at the first i, j, k
                    // knots of the clouds of r, s, t.
                    let args: Vec<DVec2> = (0..3)
                        .flat_map(|corner| (0..beta[corner]).map(move |x| clouds[corner][x]))
                        .collect();
                    f += n[s] * blossom(args[0], args[1]);
                }
            }
            let want = blossom(u, u);
            assert!(
                (f - want).abs() < 1e-10 * want.abs().max(1.0),
                "{f} vs {want} at {u}"
            );
        }
    }

    #[test]
    fn the_recursion_does_not_depend_on_the_knot_triple() {
        let (uv, tris) = jittered_domain(5, 5);
        let k = knot_clouds(&uv, &tris).unwrap();
        let t = tris[9];
        let knots: Vec<DVec2> = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0)]
            .iter()
            .map(|&(c, x)| k.knots[t[c] as usize][x])
            .collect();
        for u in points_of(&uv, &tris).into_iter().take(60) {
            let m = simplex_spline(u, &knots);
            // Another first triple: the knots in reverse and rotated order.
            for rot in 1..5 {
                let mut other = knots.clone();
                other.reverse();
                other.rotate_left(rot);
                let n = simplex_spline(u, &other);
                assert!(
                    (m - n).abs() <= 1e-12 * m.abs().max(1.0),
                    "{m} vs {n} at {u}"
                );
            }
        }
    }
}

mod knots_fixture {
    use glam::DVec2;

    use super::grid;

    /// A jittered grid domain: points and counter-clockwise triangles.
    pub fn jittered_domain(cols: u32, rows: u32) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let uv = (0..cols * rows)
            .map(|k| {
                let (c, r) = ((k % cols) as f64, (k / cols) as f64);
                let inner = c > 0.0 && r > 0.0 && c < (cols - 1) as f64 && r < (rows - 1) as f64;
                let j = if inner { 0.3 } else { 0.0 };
                DVec2::new(c + j * next(), r + j * next())
            })
            .collect();
        (uv, grid(cols, rows))
    }

    /// Every vertex, every edge midpoint and three points inside each
    /// triangle (the domain's border included).
    pub fn points_of(uv: &[DVec2], tris: &[[u32; 3]]) -> Vec<DVec2> {
        let mut out: Vec<DVec2> = uv.to_vec();
        for t in tris {
            let [a, b, c] = t.map(|v| uv[v as usize]);
            out.extend([(a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0]);
            out.extend([
                a * 0.6 + b * 0.3 + c * 0.1,
                a * 0.2 + b * 0.2 + c * 0.6,
                (a + b + c) / 3.0,
            ]);
        }
        out
    }
}
