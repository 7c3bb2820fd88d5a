//! The DMS room from the basis on: the support neighbourhoods, the f32
//! basis against the f64 oracle, the invariants of the issue (partition of
//! unity, N ≥ 0, ∫N = d/12, quadratic reproduction, affine invariance,
//! convex hull, C¹ across parameter edges, one owner per parameter point),
//! the control nets and fran_cut end to end. GPU parity is in
//! tests/parity/dms_*.rs.

mod common;

use chisel::dms::basis::{BasisInput, cpu as basis_cpu};
use chisel::dms::fit::ControlMap;
use chisel::dms::oracle::{self, bsplines, half_open, orient, simplex_spline};
use chisel::dms::spline::lattice_params;
use chisel::dms::surface::{SurfaceInput, cpu as surface_cpu};
use chisel::dms::{Domain, Fit, Projection, SplineOptions, knot_clouds, lattice, spline};
use chisel::gpu::Backend;
use chisel::{Error, TriMesh};
use glam::{DVec2, DVec3, Vec3};

/// A jittered `cols × rows` grid: parameter points, and a mesh over them
/// at height `z = 0.2·sin(x)·cos(0.7·y)`.
fn jittered(cols: usize, rows: usize) -> (Vec<DVec2>, TriMesh) {
    let mut next = common::xorshift(0x5eed);
    let mut r = move || (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    let mut uv = Vec::new();
    for j in 0..rows {
        for i in 0..cols {
            let inner = i > 0 && j > 0 && i < cols - 1 && j < rows - 1;
            let s = if inner { 0.3 } else { 0.0 };
            uv.push(DVec2::new(i as f64 + s * r(), j as f64 + s * r()));
        }
    }
    let uv2 = uv.clone();
    let mesh = common::grid_mesh(cols, rows, move |i, j| {
        let p = uv2[j * cols + i];
        Vec3::new(
            p.x as f32,
            p.y as f32,
            (0.2 * p.x.sin() * (0.7 * p.y).cos()) as f32,
        )
    });
    (uv, mesh)
}

fn domain_of(uv: &[DVec2], mesh: &TriMesh) -> Domain {
    let clouds = knot_clouds(uv, &mesh.triangles).unwrap();
    Domain::new(&mesh.triangles, &clouds)
}

/// Lattice points at accuracy `n` plus points near every knot line.
fn sample_points(uv: &[DVec2], mesh: &TriMesh, n: u32) -> Vec<DVec2> {
    let l = lattice(&mesh.triangles, mesh.n_vertices(), n).unwrap();
    lattice_params(&l, uv, &mesh.triangles)
}

/// The f32 rows as (control, weight) lists per point.
fn mirror_rows(domain: &Domain, points: &[DVec2]) -> Vec<Vec<(u32, [f32; 4])>> {
    let input = BasisInput::new(domain, points).unwrap();
    let w = basis_cpu::dms_basis(&input);
    (0..points.len())
        .map(|p| {
            let (lo, hi) = (
                input.rows.offsets[p] as usize,
                input.rows.offsets[p + 1] as usize,
            );
            (lo..hi).map(|k| (input.rows.targets[k], w[k])).collect()
        })
        .collect()
}

#[test]
fn the_grid_neighbourhood_equals_the_brute_force_one() {
    let (uv, mesh) = jittered(9, 7);
    let d = domain_of(&uv, &mesh);
    let mut pts = sample_points(&uv, &mesh, 6);
    // Points around and outside the domain too.
    pts.extend((0..200).map(|k| DVec2::new(-1.5 + 0.06 * k as f64, -1.0 + 0.045 * k as f64)));
    let grid = d.supports.candidates(&pts);
    assert_eq!(grid, d.supports.brute_force(&pts));
    // Every point of the domain has its own triangle among the candidates.
    assert!((0..pts.len()).all(|p| grid.row(p).len() <= mesh.n_triangles()));
    let mean = grid.targets.len() as f64 / pts.len() as f64;
    eprintln!("mean contributing triangles per point: {mean:.2}");
    if let Some(fran) = common::real_mesh("fran_cut.vtk") {
        let s =
            chisel::dms::SplineDomain::new(&fran, &Projection::Cylinder, 3, Backend::Cpu).unwrap();
        let pts = lattice_params(&s.lattice, &s.param.uv, &fran.triangles);
        let sub: Vec<DVec2> = pts.iter().step_by(7).copied().collect();
        assert_eq!(
            s.domain.supports.candidates(&sub),
            s.domain.supports.brute_force(&sub)
        );
    }
}

#[test]
fn every_inner_parameter_point_has_one_owner() {
    let (uv, mesh) = jittered(7, 6);
    let tri = |t: &[u32; 3]| t.map(|v| uv[v as usize]);
    let pts = sample_points(&uv, &mesh, 5);
    let (mut inner, mut border) = (0, 0);
    for u in pts {
        let owners = mesh
            .triangles
            .iter()
            .filter(|t| half_open(u, tri(t)))
            .count();
        let on_border = u.x == 0.0 || u.y == 0.0 || u.x == 6.0 || u.y == 5.0;
        if on_border {
            assert!(owners <= 1, "{u}: {owners} owners");
            border += 1;
        } else {
            assert_eq!(owners, 1, "{u}");
            inner += 1;
        }
    }
    assert!(inner > 200 && border > 30, "{inner} {border}");
}

#[test]
fn the_f32_mirror_follows_the_oracle() {
    for (what, uv, mesh) in [("jittered", jittered(8, 6).0, jittered(8, 6).1)]
        .into_iter()
        .chain(common::real_mesh("fran_cut.vtk").map(|m| {
            let p = chisel::dms::parametrise(&m, &Projection::Cylinder).unwrap();
            ("fran_cut", p.uv, m)
        }))
    {
        let d = domain_of(&uv, &mesh);
        let all = sample_points(&uv, &mesh, 4);
        let pts: Vec<DVec2> = all
            .iter()
            .step_by(if what == "fran_cut" { 9 } else { 1 })
            .copied()
            .collect();
        let rows = mirror_rows(&d, &pts);
        let (mut worst_n, mut worst_g, mut worst_sum) = (0.0f64, 0.0f64, 0.0f64);
        for (u, row) in pts.iter().zip(&rows) {
            let want = oracle::weights(&d, *u);
            assert_eq!(
                row.iter().map(|e| e.0).collect::<Vec<_>>(),
                want.iter().map(|e| e.0).collect::<Vec<_>>(),
                "{what}: controls at {u}"
            );
            let gscale = want
                .iter()
                .map(|e| e.1[1].abs().max(e.1[2].abs()))
                .fold(0.0, f64::max);
            for ((_, w32), (_, w64)) in row.iter().zip(&want) {
                worst_n = worst_n.max((w32[0] as f64 - w64[0]).abs());
                for k in 1..3 {
                    worst_g = worst_g.max((w32[k] as f64 - w64[k]).abs() / gscale);
                }
            }
            let s: f64 = row.iter().map(|e| e.1[0] as f64).sum();
            worst_sum = worst_sum.max((s - 1.0).abs());
        }
        eprintln!(
            "{what}: |N32 − N64| ≤ {worst_n:e}, |∇N32 − ∇N64| ≤ {worst_g:e} · max|∇N|, |Σ N32 − 1| ≤ {worst_sum:e}"
        );
        assert!(worst_n <= 2e-5, "{what}: {worst_n:e}");
        assert!(worst_g <= 1e-4, "{what}: {worst_g:e}");
        assert!(worst_sum <= 2e-5, "{what}: {worst_sum:e}");
    }
}

/// `conv` cut by the line through `a, b`: the parts on either side.
fn split(poly: &[DVec2], a: DVec2, b: DVec2) -> Vec<Vec<DVec2>> {
    let side = |p: DVec2| (b - a).perp_dot(p - a);
    let mut parts = vec![Vec::new(), Vec::new()];
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            parts[0].push(p);
        }
        if sp <= 0.0 {
            parts[1].push(p);
        }
        if (sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0) {
            let x = p + (q - p) * (sp / (sp - sq));
            parts[0].push(x);
            parts[1].push(x);
        }
    }
    parts.into_iter().filter(|p| p.len() >= 3).collect()
}

/// ∫ M(u | knots) over the plane: the hull cut along every knot line into
/// cells where M is one quadratic, each fan-triangulated and integrated by
/// the degree-2-exact three-point rule.
fn integral(knots: &[DVec2]) -> f64 {
    let mut hull: Vec<DVec2> = knots.to_vec();
    hull.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut h: Vec<DVec2> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let pts: Vec<DVec2> = if pass == 0 {
            hull.clone()
        } else {
            hull.iter().rev().copied().collect()
        };
        for p in pts {
            while h.len() >= start + 2 && orient(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    let mut cells = vec![h];
    for i in 0..knots.len() {
        for j in i + 1..knots.len() {
            cells = cells
                .iter()
                .flat_map(|c| split(c, knots[i], knots[j]))
                .collect();
        }
    }
    let mut sum = 0.0;
    for c in cells {
        for k in 1..c.len() - 1 {
            let (a, b, d) = (c[0], c[k], c[k + 1]);
            let area = orient(a, b, d).abs() / 2.0;
            for (x, y, z) in [(4.0, 1.0, 1.0), (1.0, 4.0, 1.0), (1.0, 1.0, 4.0)] {
                let q = (a * x + b * y + d * z) / 6.0;
                sum += area / 3.0 * simplex_spline(q, knots);
            }
        }
    }
    sum
}

#[test]
fn every_bspline_integrates_to_its_triangle_over_twelve() {
    let (uv, mesh) = jittered(5, 4);
    let clouds = knot_clouds(&uv, &mesh.triangles).unwrap();
    for t in mesh.triangles.iter().step_by(3) {
        let c = t.map(|v| clouds.knots[v as usize]);
        for beta in chisel::dms::knots::BETAS {
            let v: Vec<DVec2> = chisel::dms::knots::knot_set(beta)
                .into_iter()
                .map(|k| c[k / 3][k % 3])
                .collect();
            let d = orient(c[0][beta[0]], c[1][beta[1]], c[2][beta[2]]);
            let got = d * integral(&v);
            let want = d / 12.0;
            assert!(
                (got - want).abs() <= 1e-12 * want.abs(),
                "{beta:?}: {got} vs {want}"
            );
        }
    }
    // Negative control: a wrong normalisation (d/6) is told apart.
    let t = mesh.triangles[0].map(|v| clouds.knots[v as usize]);
    let v: Vec<DVec2> = [(0, 0), (0, 1), (0, 2), (1, 0), (2, 0)]
        .map(|(a, b)| t[a][b])
        .to_vec();
    assert!((integral(&v) - 1.0 / 6.0).abs() > 0.01);
}

/// F and ∇F (f64 oracle) at `u` for controls `c`.
fn oracle_surface(d: &Domain, c: &[DVec3], u: DVec2) -> (DVec3, DVec3, DVec3) {
    let mut f = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for (k, w) in oracle::weights(d, u) {
        let x = c[k as usize];
        f.0 += w[0] * x;
        f.1 += w[1] * x;
        f.2 += w[2] * x;
    }
    f
}

#[test]
fn the_surface_is_c1_across_parameter_edges() {
    let (uv, mesh) = jittered(6, 5);
    let d = domain_of(&uv, &mesh);
    let mut next = common::xorshift(7);
    let mut r = move || (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    let c: Vec<DVec3> = (0..d.n_controls())
        .map(|_| DVec3::new(r(), r(), r()))
        .collect();
    let h = 1e-7;
    let mut checked = 0;
    let mut worst = (0.0f64, 0.0f64);
    for &[a, b] in &d.edges {
        let (pa, pb) = (uv[a as usize], uv[b as usize]);
        let interior = |p: DVec2| p.x > 0.0 && p.y > 0.0 && p.x < 5.0 && p.y < 4.0;
        if !(interior((pa + pb) / 2.0) && (pa.x != pb.x || interior(pa))) {
            continue;
        }
        let n = (pb - pa).perp().normalize();
        for s in [0.3, 0.5, 0.77] {
            let u = pa + s * (pb - pa);
            let (f0, fu0, fv0) = oracle_surface(&d, &c, u - h * n);
            let (f1, fu1, fv1) = oracle_surface(&d, &c, u + h * n);
            let g = fu0.length().max(fv0.length());
            worst.0 = worst.0.max((f1 - f0).length() / g);
            worst.1 = worst
                .1
                .max((fu1 - fu0).length().max((fv1 - fv0).length()) / g);
            checked += 1;
        }
    }
    eprintln!(
        "C¹ across {checked} edge points: value jump {:e}, gradient jump {:e} (×|∇F|, h = {h:e})",
        worst.0, worst.1
    );
    assert!(checked > 40);
    assert!(worst.0 <= 4.0 * h, "value jump {:e}", worst.0);
    assert!(worst.1 <= 1e-4, "gradient jump {:e}", worst.1);
    // The analytic gradient is the derivative: central differences agree.
    let u = DVec2::new(2.31, 1.77);
    let (_, fu, fv) = oracle_surface(&d, &c, u);
    let e = 1e-6;
    let du = (oracle_surface(&d, &c, u + DVec2::X * e).0
        - oracle_surface(&d, &c, u - DVec2::X * e).0)
        / (2.0 * e);
    let dv = (oracle_surface(&d, &c, u + DVec2::Y * e).0
        - oracle_surface(&d, &c, u - DVec2::Y * e).0)
        / (2.0 * e);
    assert!(
        (du - fu).length() <= 1e-6 * fu.length().max(1.0),
        "{du} vs {fu}"
    );
    assert!(
        (dv - fv).length() <= 1e-6 * fv.length().max(1.0),
        "{dv} vs {fv}"
    );
    // Negative control: the piecewise-linear mesh is not C¹ — its gradient
    // jumps across the same edges by O(1).
    let pl = |u: DVec2| -> DVec2 {
        let t = d.locate(u).unwrap();
        let [a, b, c3] = mesh.triangles[t as usize].map(|v| uv[v as usize]);
        let z = |p: DVec2| 0.2 * p.x.sin() * (0.7 * p.y).cos();
        let m = glam::DMat2::from_cols(b - a, c3 - a);
        m.inverse().transpose() * DVec2::new(z(b) - z(a), z(c3) - z(a))
    };
    let [a, b] = d.edges[d.edges.len() / 2];
    let (pa, pb) = (uv[a as usize], uv[b as usize]);
    let n = (pb - pa).perp().normalize();
    let mid = (pa + pb) / 2.0;
    assert!((pl(mid + 1e-3 * n) - pl(mid - 1e-3 * n)).length() > 1e-3);
}

#[test]
fn quadratics_are_reproduced_through_the_f32_rows_and_identify_is_not_exact() {
    let (uv, mesh) = jittered(7, 5);
    let d = domain_of(&uv, &mesh);
    // q(u) = (uᵀAu + b·u + c) per coordinate; blossom P(x, y).
    let q = |x: DVec2, y: DVec2| {
        DVec3::new(
            0.3 * x.x * y.x - 0.2 * (x.x * y.y + x.y * y.x)
                + 0.1 * x.y * y.y
                + 0.5 * (x.x + y.x)
                + 1.0,
            -0.1 * x.x * y.x + 0.4 * x.y * y.y - 0.25 * (x.y + y.y),
            0.05 * (x.x * y.y + x.y * y.x) + 2.0,
        )
    };
    let k = |v: u32, i: usize| d.knots[v as usize][i];
    let controls: Vec<DVec3> = (0..d.n_vertices as u32)
        .map(|v| q(k(v, 0), k(v, 1)))
        .chain(d.edges.iter().map(|&[a, b]| q(k(a, 0), k(b, 0))))
        .collect();
    let pts = sample_points(&uv, &mesh, 5);
    let input = BasisInput::new(&d, &pts).unwrap();
    let rows = SurfaceInput::over_controls(
        &chisel::dms::basis::BasisRows {
            rows: input.rows.clone(),
            weights: basis_cpu::dms_basis(&input),
        },
        d.n_controls(),
    );
    let src: Vec<[f32; 4]> = controls
        .iter()
        .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
        .collect();
    let s = surface_cpu::dms_surface(&rows, &src);
    let worst = pts
        .iter()
        .zip(&s.positions)
        .map(|(u, f)| (DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64) - q(*u, *u)).length())
        .fold(0.0, f64::max);
    eprintln!("quadratic reproduction, f32 path: {worst:e}");
    assert!(worst <= 1e-4, "{worst:e}");
    // Negative control: point identification (vertex controls = q at the
    // vertex) does not reproduce even this smooth function.
    let ident: Vec<[f32; 4]> = (0..d.n_vertices as u32)
        .map(|v| q(k(v, 0), k(v, 0)))
        .chain(
            d.edges
                .iter()
                .map(|&[a, b]| (q(k(a, 0), k(a, 0)) + q(k(b, 0), k(b, 0))) / 2.0),
        )
        .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
        .collect();
    let s = surface_cpu::dms_surface(&rows, &ident);
    let off = pts
        .iter()
        .zip(&s.positions)
        .map(|(u, f)| (DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64) - q(*u, *u)).length())
        .fold(0.0, f64::max);
    assert!(
        off > 100.0 * worst,
        "identify {off:e} vs blossoms {worst:e}"
    );
}

#[test]
fn affine_maps_commute_and_points_stay_in_the_hull_of_their_controls() {
    let (uv, mesh) = jittered(6, 6);
    let d = domain_of(&uv, &mesh);
    let pts = sample_points(&uv, &mesh, 4);
    let input = BasisInput::new(&d, &pts).unwrap();
    let basis = chisel::dms::basis::BasisRows {
        rows: input.rows.clone(),
        weights: basis_cpu::dms_basis(&input),
    };
    let rows = SurfaceInput::over_controls(&basis, d.n_controls());
    let controls: Vec<Vec3> = ControlMap::identify(&d)
        .apply(&mesh.positions)
        .iter()
        .map(|c| c.as_vec3())
        .collect();
    let src: Vec<[f32; 4]> = controls.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
    let s = surface_cpu::dms_surface(&rows, &src);
    let m = glam::Mat3::from_cols_array(&[0.8, 0.3, -0.2, -0.4, 1.1, 0.5, 0.1, 0.2, 0.9]);
    let t = Vec3::new(3.0, -1.0, 0.5);
    let moved: Vec<[f32; 4]> = controls
        .iter()
        .map(|p| (m * *p + t).extend(0.0).to_array())
        .collect();
    let s2 = surface_cpu::dms_surface(&rows, &moved);
    for (p, (a, b)) in s.positions.iter().zip(&s2.positions).enumerate() {
        let want = m * Vec3::new(a[0], a[1], a[2]) + t;
        assert!(
            (want - Vec3::new(b[0], b[1], b[2])).length() < 1e-5,
            "point {p}"
        );
        // Convex hull: weights ≥ 0 (to rounding) summing to 1, and the
        // point inside the box of its row's controls.
        let (lo, hi) = (
            rows.rows.offsets[p] as usize,
            rows.rows.offsets[p + 1] as usize,
        );
        let ws = &rows.weights[lo..hi];
        assert!(ws.iter().all(|w| w[0] >= -1e-6), "point {p}: {ws:?}");
        let (mut bl, mut bh) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for &v in &rows.rows.targets[lo..hi] {
            bl = bl.min(controls[v as usize]);
            bh = bh.max(controls[v as usize]);
        }
        let f = Vec3::new(a[0], a[1], a[2]);
        assert!(
            f.cmpge(bl - 1e-5).all() && f.cmple(bh + 1e-5).all(),
            "point {p}: {f} not in {bl}–{bh}"
        );
    }
}

#[test]
fn fran_cut_spline_at_n_5() {
    let Some(fran) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let opts = SplineOptions {
        projection: Projection::Cylinder,
        fit: Fit::Identify,
        data: None,
        n: 5,
    };
    let (sd, s) = spline(&fran, &opts, Backend::Cpu).unwrap();
    assert_eq!(
        (s.mesh.n_vertices(), s.mesh.n_triangles()),
        (34_161, 67_584)
    );
    // No cracks, no duplicated points: each directed edge once, each
    // undirected edge in at most two triangles, walked both ways.
    let mut uses = std::collections::HashMap::new();
    for t in &s.mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0i32) += if a < b { 1 } else { -1 } * 2;
        }
    }
    assert!(uses.values().all(|&s| s == 0 || s.abs() == 2));
    let boundary = uses.values().filter(|&&s| s != 0).count();
    // The input's boundary edges, each split into n − 1 = 4.
    let input_boundary = {
        let mut u = std::collections::HashMap::new();
        for t in &fran.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *u.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        u.values().filter(|&&c| c == 1).count()
    };
    assert_eq!(boundary, 4 * input_boundary);
    // Normals: unit, and on the side of the output triangles' winding.
    let nx = |k: usize| &s.mesh.scalars[k].values;
    let mut agree = 0;
    for t in &s.mesh.triangles {
        let [a, b, c] = t.map(|v| s.mesh.positions[v as usize]);
        let face = (b - a).cross(c - a);
        let v = t[0] as usize;
        let n = Vec3::new(nx(0)[v], nx(1)[v], nx(2)[v]);
        assert!((n.length() - 1.0).abs() < 1e-4);
        if face.dot(n) > 0.0 {
            agree += 1;
        }
    }
    assert!(
        agree as f64 >= 0.99 * s.mesh.n_triangles() as f64,
        "{agree}"
    );
    // The smooth skin stays near the mesh: the distance field is a small
    // fraction of the mean edge length.
    let dist = &s.mesh.scalars[3].values;
    let max = dist.iter().copied().fold(0.0f32, f32::max);
    let edge: f32 = sd
        .domain
        .edges
        .iter()
        .map(|&[a, b]| fran.positions[a as usize].distance(fran.positions[b as usize]))
        .sum::<f32>()
        / sd.domain.edges.len() as f32;
    eprintln!(
        "fran_cut n=5: max |F − mesh| = {max:e} (mean edge {edge:e}), knot quality {:.3}, fit rms {:e}",
        sd.knot_quality, s.fit.rms
    );
    assert!(max < 0.5 * edge, "{max} vs {edge}");
    // Least squares fits the mesh data better than identification.
    let lsq = SplineOptions {
        fit: Fit::LeastSquares { fairing: 0.0 },
        ..opts
    };
    let (_, l) = spline(&fran, &lsq, Backend::Cpu).unwrap();
    eprintln!(
        "fran_cut lsq: rms {:e} max {:e} ({} CG iterations) vs identify rms {:e}",
        l.fit.rms, l.fit.max, l.fit.iterations, s.fit.rms
    );
    assert!(l.fit.rms < 0.5 * s.fit.rms);
}

#[test]
fn least_squares_reproduces_a_plane_and_fairing_smooths() {
    let (uv, mesh) = jittered(8, 7);
    // A planar mesh: identification slides within the plane, least squares
    // against the mesh data reproduces it.
    let flat = TriMesh::new(
        mesh.positions
            .iter()
            .map(|p| Vec3::new(p.x, p.y, 0.3 * p.x - 0.2 * p.y + 1.0))
            .collect(),
        mesh.triangles.clone(),
    )
    .unwrap();
    let opts = SplineOptions {
        projection: Projection::Given(uv.clone()),
        fit: Fit::LeastSquares { fairing: 0.0 },
        data: None,
        n: 4,
    };
    let (_, s) = spline(&flat, &opts, Backend::Cpu).unwrap();
    assert!(s.fit.rms < 1e-6 && s.fit.max < 1e-5, "{:?}", s.fit);
    let (_, id) = spline(
        &flat,
        &SplineOptions {
            fit: Fit::Identify,
            ..opts.clone()
        },
        Backend::Cpu,
    )
    .unwrap();
    assert!(id.fit.rms > 1e-3, "{:?}", id.fit);
    // Fairing trades fit for smoothness: a larger residual.
    let (_, f) = spline(
        &mesh,
        &SplineOptions {
            fit: Fit::LeastSquares { fairing: 0.1 },
            ..opts.clone()
        },
        Backend::Cpu,
    )
    .unwrap();
    let (_, f0) = spline(
        &mesh,
        &SplineOptions {
            fit: Fit::LeastSquares { fairing: 0.0 },
            ..opts.clone()
        },
        Backend::Cpu,
    )
    .unwrap();
    assert!(f.fit.rms > f0.fit.rms);
    // Given UVs cannot project extra data; a negative weight is refused.
    let with_data = SplineOptions {
        data: Some(vec![Vec3::ZERO]),
        ..opts.clone()
    };
    assert!(
        matches!(spline(&mesh, &with_data, Backend::Cpu), Err(Error::InvalidParameter { name, .. }) if name == "data")
    );
    let bad = SplineOptions {
        fit: Fit::LeastSquares { fairing: -1.0 },
        ..opts
    };
    assert!(
        matches!(spline(&mesh, &bad, Backend::Cpu), Err(Error::InvalidParameter { name, .. }) if name == "fairing")
    );
}

#[test]
fn oracle_bsplines_sum_with_the_rows() {
    // The rows' N equal the per-triangle oracle values summed per control.
    let (uv, mesh) = jittered(5, 5);
    let d = domain_of(&uv, &mesh);
    let u = DVec2::new(1.7, 2.2);
    let w = oracle::weights(&d, u);
    let total: f64 = d
        .supports
        .at(u)
        .iter()
        .map(|&t| {
            bsplines(u, mesh.triangles[t as usize].map(|v| d.knots[v as usize]))
                .iter()
                .sum::<f64>()
        })
        .sum();
    assert!((w.iter().map(|e| e.1[0]).sum::<f64>() - total).abs() < 1e-14);
    assert!((total - 1.0).abs() < 1e-12);
}

/// Mean `1 − n₁·n₂` over the interior edges of `m` (unit face normals):
/// how faceted the shading looks.
fn roughness(m: &TriMesh) -> f64 {
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| m.positions[v as usize].as_dvec3());
        (b - a).cross(c - a).normalize_or_zero()
    };
    let mut faces: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    let (mut sum, mut count) = (0.0, 0);
    for (i, t) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if let Some(j) = faces.insert((a.min(b), a.max(b)), i) {
                sum += 1.0 - normal(t).dot(normal(&m.triangles[j]));
                count += 1;
            }
        }
    }
    sum / count as f64
}

#[test]
fn quasi_interpolation_reproduces_quadratics_and_smooths_the_facets() {
    // A quadratic height field over its own parameter plane: the quasi
    // controls are its blossoms, so the spline is the surface itself.
    let (uv, mesh) = jittered(8, 7);
    let q = |u: DVec2| 0.3 * u.x * u.x - 0.2 * u.x * u.y + 0.1 * u.y * u.y + 0.5 * u.x - 1.0;
    let surf = TriMesh::new(
        uv.iter()
            .map(|u| Vec3::new(u.x as f32, u.y as f32, q(*u) as f32))
            .collect(),
        mesh.triangles.clone(),
    )
    .unwrap();
    let opts = SplineOptions {
        projection: Projection::Given(uv.clone()),
        fit: Fit::Quasi,
        data: None,
        n: 5,
    };
    let (sd, s) = spline(&surf, &opts, Backend::Cpu).unwrap();
    let pts = lattice_params(&sd.lattice, &uv, &mesh.triangles);
    let worst = pts
        .iter()
        .zip(&s.mesh.positions)
        .map(|(u, f)| (f.as_dvec3() - DVec3::new(u.x, u.y, q(*u))).length())
        .fold(0.0, f64::max);
    eprintln!("quasi-interpolation of a quadratic: {worst:e}");
    assert!(worst < 1e-4, "{worst:e}");
    // Identification of the same data is off by the knot offsets.
    let (_, id) = spline(
        &surf,
        &SplineOptions {
            fit: Fit::Identify,
            ..opts
        },
        Backend::Cpu,
    )
    .unwrap();
    let off = pts
        .iter()
        .zip(&id.mesh.positions)
        .map(|(u, f)| (f.as_dvec3() - DVec3::new(u.x, u.y, q(*u))).length())
        .fold(0.0, f64::max);
    assert!(off > 100.0 * worst, "{off:e}");
    // On fran_cut the quasi skin is less faceted than identification's.
    let Some(fran) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let run = |fit| {
        let o = SplineOptions {
            projection: Projection::Cylinder,
            fit,
            data: None,
            n: 5,
        };
        spline(&fran, &o, Backend::Cpu).unwrap().1
    };
    let (rq, ri) = (
        roughness(&run(Fit::Quasi).mesh),
        roughness(&run(Fit::Identify).mesh),
    );
    eprintln!("fran_cut n=5 roughness: quasi {rq:e}, identify {ri:e}");
    assert!(rq < 0.7 * ri, "{rq:e} vs {ri:e}");
}
