//! Synthetic volumes: random fields, every single-cell case, balls and tori,
//! spacing and origin, open borders, labels, the bounding-box forest, and
//! thread-count independence.

use chisel::Backend;
use chisel::foundation::Forest;
use chisel::mc::{IsoSpec, McOptions, marching_cubes};
use chisel::volume::{Volume, VolumeData};
use glam::Vec3;

use crate::oracle::check_topology;
use crate::{CLOSE, ball, random_volume, torus};

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

/// Open borders: per group, the border edges (directed edges whose reverse
/// no triangle has) and χ = V − E + F counted by brute force over the
/// mesh, on random fields whose surfaces meet every face of the grid.
#[test]
fn open_border_figures_match_a_brute_force_count() {
    use std::collections::HashSet;
    let open = McOptions::default();
    let mut with_border = 0;
    for seed in 1..=6u64 {
        let vol = random_volume(seed, [9, 8, 7]);
        for level in [60.5f32, 128.0, 200.5] {
            let s = marching_cubes(&vol, IsoSpec::Level(level), &open, Backend::Cpu).unwrap();
            let tris = &s.mesh.triangles;
            let directed: HashSet<(u32, u32)> = tris
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .collect();
            let n = s.groups.len();
            let (mut border, mut faces) = (vec![0u32; n], vec![0i64; n]);
            let mut vertices = vec![HashSet::new(); n];
            let mut area = vec![0f64; n];
            let p = |v: u32| s.mesh.positions[v as usize].as_dvec3();
            for (t, &g) in tris.iter().zip(&s.triangle_groups) {
                let g = g as usize;
                faces[g] += 1;
                vertices[g].extend(t.iter().copied());
                area[g] += 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
                for k in 0..3 {
                    if !directed.contains(&(t[(k + 1) % 3], t[k])) {
                        border[g] += 1;
                    }
                }
            }
            for (g, group) in s.groups.iter().enumerate() {
                let edges = (3 * faces[g] + i64::from(border[g])) / 2;
                let euler = vertices[g].len() as i64 - edges + faces[g];
                assert_eq!(
                    group.boundary_edges, border[g],
                    "seed {seed} {level} group {g}"
                );
                assert_eq!(group.euler, euler, "seed {seed} {level} group {g}");
                assert_eq!(i64::from(group.triangles), faces[g]);
                assert_eq!(group.vertices as usize, vertices[g].len());
                let corners = vertices[g].iter().map(|&v| s.mesh.positions[v as usize]);
                let (lo, hi) = corners.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), q| {
                    (lo.min(q), hi.max(q))
                });
                assert_eq!(
                    (group.bbox.min, group.bbox.max),
                    (lo, hi),
                    "seed {seed} {level} group {g}"
                );
                assert!(
                    (group.area - area[g]).abs() <= 1e-9 * area[g],
                    "seed {seed} {level} group {g}"
                );
                with_border += usize::from(border[g] > 0);
            }
        }
    }
    assert!(with_border > 10, "{with_border} groups reach the border");
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
fn oblique_and_reflected_axes_place_the_surface_in_the_world() {
    // A ball off the grid centre (the torus of the fixtures is symmetric).
    let a = ball(20, 6.0, [0.5, 2.0, 3.0], [10.0, -5.0, 7.0]);
    let sa = marching_cubes(&a, IsoSpec::Level(0.0), &McOptions::default(), Backend::Cpu).unwrap();
    let q = glam::DQuat::from_axis_angle(glam::DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    for reflect in [false, true] {
        let mut axes = [glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z].map(|e| q * e);
        if reflect {
            axes[2] = -axes[2];
        }
        let b = a
            .clone()
            .with_frame(axes.map(|v| v.to_array()), None)
            .unwrap();
        let sb =
            marching_cubes(&b, IsoSpec::Level(0.0), &McOptions::default(), Backend::Cpu).unwrap();
        // Each vertex is the aligned one moved by the frame about the origin.
        let o = glam::DVec3::from(a.origin);
        for (p, w) in sa.mesh.positions.iter().zip(&sb.mesh.positions) {
            let d = p.as_dvec3() - o;
            let want = o + axes[0] * d.x + axes[1] * d.y + axes[2] * d.z;
            assert!(
                (want - w.as_dvec3()).abs().max_element() < 1e-4,
                "{want} vs {w}"
            );
        }
        // Still wound outward, with the same volume (a reflection reverses
        // the index-space winding).
        let (va, vb) = (sa.mesh.signed_volume(), sb.mesh.signed_volume());
        assert!(
            va > 0.0 && (vb - va).abs() < 1e-3 * va,
            "reflect {reflect}: {va} vs {vb}"
        );
        assert!((sb.groups[0].volume - sa.groups[0].volume).abs() < 1e-3 * va);
    }
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
    assert!(
        matches!(
            err,
            chisel::Error::InvalidData {
                at: chisel::Position::Item { kind: "sample", .. },
                ..
            }
        ),
        "{err}"
    );
    // Checked while the rows are packed: the position is the sample's, on
    // an open and a closed border, with and without grouping.
    let (nx, ny) = (5, 4);
    let (x, y, z) = (3, 2, 1);
    let mut data = vec![0.0f32; nx * ny * 3];
    data[x + nx * (y + ny * z)] = f32::INFINITY;
    let bad = Volume::new([5, 4, 3], [1.0; 3], [0.0; 3], VolumeData::F32(data)).unwrap();
    for close_border in [false, true] {
        for mesh_only in [false, true] {
            let opts = McOptions {
                close_border,
                mesh_only,
            };
            let err = marching_cubes(&bad, IsoSpec::Level(0.5), &opts, Backend::Cpu).unwrap_err();
            assert!(
                err.to_string().contains("at (3, 2, 1) is not finite"),
                "{err}"
            );
        }
    }
    assert!(matches!(
        marching_cubes(&vol, IsoSpec::Level(f32::NAN), &CLOSE, Backend::Cpu),
        Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "level"
    ));
}

#[test]
fn forest_covers_every_triangle_once_with_true_boxes() {
    let vol = random_volume(7, [12, 11, 10]);
    let s = marching_cubes(&vol, IsoSpec::Level(128.0), &CLOSE, Backend::Cpu).unwrap();
    let f = &s.forest;
    assert_eq!(f.groups.len(), s.groups.len());
    // The build's block of each cell (by shifts, decoded once per row)
    // against the blocks computed here, given as keys of a one-cell leaf.
    let b = chisel::mc::LEAF_BLOCK;
    let g = s.grid.dims.map(|d| d - 1);
    let block = |key: usize| {
        let (x, y, z) = (key % g[0], (key / g[0]) % g[1], key / (g[0] * g[1]));
        x / b + f.cell_dims[0] * (y / b + f.cell_dims[1] * (z / b))
    };
    let keys: Vec<u32> = (s.triangle_cells.iter())
        .map(|&c| block(c as usize) as u32)
        .collect();
    let by_keys = Forest::build(
        s.mesh.view(),
        &keys,
        f.cell_dims,
        1,
        &s.triangle_groups,
        s.groups.len(),
    );
    assert_eq!(
        Forest {
            closed_outward: true,
            ..by_keys
        },
        *f
    );
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
                        let key = block(s.triangle_cells[t as usize] as usize);
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

/// The stitch numbers every vertex's group from the chunks' union-find
/// nodes (the seam layers' from the chunk below): it must be the group of
/// every triangle using the vertex, at any number of chunks.
#[test]
fn vertex_groups_are_their_triangles_groups_at_any_thread_count() {
    let vol = random_volume(5, [37, 29, 41]);
    for close in [false, true] {
        let field = chisel::mc::Field::new(&vol, IsoSpec::Level(127.5), close).unwrap();
        for threads in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let raw = pool
                .install(|| chisel::mc::cpu::marching_cubes(&field, true))
                .unwrap();
            assert!(raw.n_groups > 1, "want several groups");
            assert_eq!(raw.vertex_groups.len(), raw.positions.len());
            let mut used = vec![false; raw.positions.len()];
            for (t, &g) in raw.triangles.iter().zip(&raw.groups) {
                for &v in t {
                    assert_eq!(
                        raw.vertex_groups[v as usize], g,
                        "vertex {v}, {threads} threads, close {close}"
                    );
                    used[v as usize] = true;
                }
            }
            assert!(used.iter().all(|&u| u), "every vertex is used");
        }
    }
}

#[test]
fn mesh_only_gives_the_same_mesh_without_groups() {
    for (k, close_border) in [false, true].into_iter().enumerate() {
        let vol = random_volume(11 + k as u64, [13, 9, 17]);
        let iso = IsoSpec::Level(128.0);
        let full = McOptions {
            close_border,
            mesh_only: false,
        };
        let bare = McOptions {
            close_border,
            mesh_only: true,
        };
        let a = marching_cubes(&vol, iso, &full, Backend::Cpu).unwrap();
        let b = marching_cubes(&vol, iso, &bare, Backend::Cpu).unwrap();
        assert!(!a.groups.is_empty() && !a.mesh.triangles.is_empty());
        assert_eq!(a.mesh.positions, b.mesh.positions);
        assert_eq!(a.mesh.triangles, b.mesh.triangles);
        assert_eq!(a.vertex_edges, b.vertex_edges);
        assert_eq!(a.triangle_cells, b.triangle_cells);
        assert!(b.groups.is_empty() && b.triangle_groups.is_empty());
        assert_eq!(b.forest, chisel::foundation::Forest::default());
    }
}
