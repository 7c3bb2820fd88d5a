//! Tissue model: network construction, plans and their validation, Δt
//! policy, the f64 oracle against analytic cases, the CPU mirror against the
//! oracle, stop criteria, and the accelerated solver's equilibrium.

mod common;

use chisel::Backend;
use chisel::mesh::TriMesh;
use chisel::tissue::network::unique_edges;
use chisel::tissue::oracle::{self, OracleState};
use chisel::tissue::phantom::{self, FRAN_GRID};
use chisel::tissue::{
    Fragments, Iterations, Material, NetworkParams, Plan, RelaxOptions, Selector, Solver,
    SpringClass, SpringNetwork, Status, Step, Stiffness, explicit, relax,
};
use glam::{DVec3, Vec3};

/// A flat `nx × ny` grid patch in the x–y plane (spacing 1), wound +z.
fn grid(nx: usize, ny: usize) -> TriMesh {
    common::grid_mesh(nx, ny, |i, j| {
        Vec3::new(i as f32, j as f32, 0.1 * ((i * j) % 3) as f32)
    })
}

fn two_spheres() -> TriMesh {
    let a = common::icosphere(1);
    let mut m = a.clone();
    let off = a.n_vertices() as u32;
    m.positions
        .extend(a.positions.iter().map(|p| *p + Vec3::new(3.0, 0.0, 0.0)));
    m.triangles
        .extend(a.triangles.iter().map(|t| t.map(|i| i + off)));
    m
}

/// With the default bone (a scaled copy), eq. 4.1 links q_i to b_i, so the
/// class counts have closed forms in #V and #E.
fn check_counts(mesh: &TriMesh) -> SpringNetwork {
    let net = SpringNetwork::build(mesh, None, &NetworkParams::default()).unwrap();
    let n = mesh.n_vertices();
    let e = unique_edges(&mesh.triangles).len();
    assert_eq!(net.n_nodes(), 3 * n);
    assert_eq!(net.n_free, 2 * n);
    assert_eq!(net.class_counts(), [e, n + 2 * e, e, n + 2 * e, e, 0]);
    // Rest length = initial length; springs unique and ordered.
    for w in net.springs.windows(2) {
        assert!((w[0].a, w[0].b) < (w[1].a, w[1].b));
    }
    for s in &net.springs {
        let (a, b) = (net.rest[s.a as usize], net.rest[s.b as usize]);
        let d = Vec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2]).length();
        assert!((d - s.rest).abs() <= 1e-6 * d.max(1.0));
    }
    // The gather CSR is the symmetric closure over free nodes, rows sorted.
    let mut expect = 0;
    for s in &net.springs {
        expect +=
            usize::from((s.a as usize) < net.n_free) + usize::from((s.b as usize) < net.n_free);
    }
    assert_eq!(net.csr.entries.len(), expect);
    for i in 0..net.n_free {
        let row = &net.csr.entries[net.csr.offsets[i] as usize..net.csr.offsets[i + 1] as usize];
        let ids: Vec<u32> = row.iter().map(|e| e & 0x0fff_ffff).collect();
        assert!(ids.windows(2).all(|w| w[0] < w[1]), "row {i} not sorted");
    }
    net
}

#[test]
fn network_counts_open_closed_and_multi_component() {
    check_counts(&grid(6, 5));
    let closed = check_counts(&common::icosphere(2));
    // Closed surface: origin at the bounding-box centre, layers nest.
    assert!(closed.origin.length() < 1e-6);
    check_counts(&two_spheres());
}

#[test]
fn default_origin_is_behind_an_open_patch_whatever_the_winding() {
    let mut m = grid(5, 5);
    // Bulge the patch toward +z so its outer side is +z.
    for p in &mut m.positions {
        p.z = 3.0 - 0.1 * ((p.x - 2.0).powi(2) + (p.y - 2.0).powi(2));
    }
    let o = chisel::tissue::default_origin(&m).unwrap();
    let lo = m.bounds().unwrap().0;
    assert_eq!(o.z, lo.z, "origin must be on the back (−z) face");
    m.flip_winding();
    assert_eq!(chisel::tissue::default_origin(&m).unwrap(), o);
}

#[test]
fn nearest_bone_links_follow_eq_4_1_with_a_real_bone_mesh() {
    let skin = common::icosphere(2);
    let mut bone = common::icosphere(1);
    for p in &mut bone.positions {
        *p = *p * 0.6 + Vec3::new(0.05, -0.02, 0.0);
    }
    let params = NetworkParams {
        origin: Some([0.0; 3]),
        ..NetworkParams::default()
    };
    let net = SpringNetwork::build(&skin, Some(&bone), &params).unwrap();
    let n = skin.n_vertices();
    let s = 0.7f64 / 0.8;
    for i in 0..n {
        let q = net.rest[n + i];
        let target = DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) * s;
        let brute = (0..bone.n_vertices())
            .min_by(|&a, &b| {
                let da = bone.positions[a].as_dvec3().distance_squared(target);
                let db = bone.positions[b].as_dvec3().distance_squared(target);
                da.total_cmp(&db).then(a.cmp(&b))
            })
            .unwrap();
        let b = (2 * n + brute) as u32;
        assert!(
            net.springs
                .iter()
                .any(|sp| sp.a == (n + i) as u32 && sp.b == b && sp.class == SpringClass::Muscle),
            "q_{i} not linked to its nearest bone vertex {brute}"
        );
    }
    // Bone nodes are fixed: no CSR rows.
    assert_eq!(net.csr.offsets.len(), 2 * n + 1);
}

#[test]
fn unused_vertices_keep_dermis_and_muscle_links() {
    let mut m = grid(4, 4);
    m.positions.push(Vec3::new(1.5, 1.5, 2.0));
    let net = SpringNetwork::build(&m, None, &NetworkParams::default()).unwrap();
    let v = (m.n_vertices() - 1) as u32;
    let n = m.n_vertices() as u32;
    let has = |a, b, c| {
        net.springs
            .iter()
            .any(|s| s.a == a && s.b == b && s.class == c)
    };
    assert!(has(v, n + v, SpringClass::Dermis));
    assert!(has(n + v, 2 * n + v, SpringClass::Muscle));
}

#[test]
fn bad_networks_are_refused() {
    let empty = TriMesh::default();
    assert!(SpringNetwork::build(&empty, None, &NetworkParams::default()).is_err());
    let m = grid(3, 3);
    let bad_scale = NetworkParams {
        subcutis_scale: f32::NAN,
        ..NetworkParams::default()
    };
    assert!(SpringNetwork::build(&m, None, &bad_scale).is_err());
    let bad_origin = NetworkParams {
        origin: Some([0.0, f32::INFINITY, 0.0]),
        ..NetworkParams::default()
    };
    let e = SpringNetwork::build(&m, None, &bad_origin).unwrap_err();
    assert!(e.to_string().contains("origin"), "{e}");
}

#[test]
fn stiffness_regions_override_springs_in_the_region() {
    let m = grid(6, 6);
    let params = NetworkParams {
        regions: vec![chisel::tissue::StiffnessRegion {
            region: Selector::Box {
                min: [-1.0, -1.0, -10.0],
                max: [2.0, 2.0, 10.0],
            },
            class: Some(SpringClass::Epidermis),
            scale: 4.0,
        }],
        ..NetworkParams::default()
    };
    let net = SpringNetwork::build(&m, None, &params).unwrap();
    assert_eq!(net.materials.len(), 7);
    assert_eq!(net.materials[6].c1, 4.0);
    let overridden = net.springs.iter().filter(|s| s.material == 6).count();
    assert!(overridden > 0);
    assert!(
        net.springs
            .iter()
            .filter(|s| s.material == 6)
            .all(|s| s.class == SpringClass::Epidermis)
    );
}

fn with_bending(c: f32) -> NetworkParams {
    NetworkParams {
        stiffness: Stiffness {
            bending: Material::linear(c),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Bend springs join the two apexes of every interior epidermis edge
/// (rest = their distance); where the apexes already share an edge (a
/// tetrahedron) the epidermis spring is kept.
#[test]
fn bend_springs_span_each_interior_edge() {
    let sphere = common::icosphere(2);
    let net = SpringNetwork::build(&sphere, None, &with_bending(0.5)).unwrap();
    let (n, e) = (sphere.n_vertices(), unique_edges(&sphere.triangles).len());
    assert_eq!(net.class_counts(), [e, n + 2 * e, e, n + 2 * e, e, e]);
    assert_eq!(net.materials[SpringClass::Bending as usize].c1, 0.5);
    let mut apexes = std::collections::HashMap::<(u32, u32), Vec<u32>>::new();
    for t in &sphere.triangles {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            apexes.entry((a, b)).or_default().push(t[(k + 2) % 3]);
        }
    }
    let mut want: Vec<(u32, u32)> = apexes
        .values()
        .map(|c| (c[0].min(c[1]), c[0].max(c[1])))
        .collect();
    want.sort_unstable();
    let got: Vec<(u32, u32)> = net
        .springs
        .iter()
        .filter(|s| s.class == SpringClass::Bending)
        .map(|s| (s.a, s.b))
        .collect();
    assert_eq!(got, want);
    // Open grid: one per interior edge; the border edges have one apex.
    let g = grid(6, 5);
    let net = SpringNetwork::build(&g, None, &with_bending(1.0)).unwrap();
    let interior = unique_edges(&g.triangles).len() - 2 * (5 + 4);
    assert_eq!(net.class_counts()[5], interior);
    let tetra = SpringNetwork::build(&common::tetra(), None, &with_bending(1.0)).unwrap();
    assert_eq!(tetra.class_counts()[5], 0);
    assert_eq!(tetra.class_counts()[0], 6);
    // Off by default; negative stiffness refused.
    let plain = SpringNetwork::build(&sphere, None, &NetworkParams::default()).unwrap();
    assert_eq!(plain.class_counts()[5], 0);
    for bad in [-1.0, f32::NAN] {
        let e = SpringNetwork::build(&sphere, None, &with_bending(bad)).unwrap_err();
        assert!(e.to_string().contains("Bending"), "{e}");
    }
}

// ---------------------------------------------------------------- plans

fn plan_err(toml: &str) -> String {
    Plan::from_toml_str(toml, "test.toml")
        .unwrap_err()
        .to_string()
}

#[test]
fn plan_validation_names_the_problem() {
    let e = plan_err("[[step]]\nselect = { vertices = [1] }\ntranslat = [1, 0, 0]\n");
    assert!(
        e.contains("translat") && e.contains("line 3, column 1"),
        "{e}"
    );
    // toml says only "duplicate key"; the message names it.
    let e = plan_err(
        "[[step]]\nselect = { vertices = [1] }\n  translate = [1, 0, 0]\n  translate = [2, 0, 0]\n",
    );
    assert!(
        e.contains("line 4, column 3") && e.contains("duplicate key `translate`"),
        "{e}"
    );
    let e =
        plan_err("[[step]]\nselect = { sphere = { center = [0,0,0], radius = 1, extra = 2 } }\n");
    assert!(e.contains("extra"), "{e}");
    let e = plan_err("[[step]]\nselect = { vertices = [1] }\nincrements = 0\n");
    assert!(e.contains("increments") && e.contains("k = 0"), "{e}");
    let e = plan_err("[[step]]\nselect = { vertices = [1] }\ntranslate = [nan, 0, 0]\n");
    assert!(e.contains("not finite"), "{e}");
    let e = plan_err("[[step]]\nselect = { vertices = [1] }\niterations = \"forever\"\n");
    assert!(e.contains("converge"), "{e}");
    let e = plan_err("[[step]]\nselect = { vertices = [] }\n");
    assert!(e.contains("empty selection"), "{e}");
    let e = plan_err("[[step]]\nselect = { sphere = { center = [0,0,0], radius = -1 } }\n");
    assert!(e.contains("radius"), "{e}");
    let e = plan_err("name = \"x\"\n");
    assert!(e.contains("step"), "{e}");
    let e = Plan::from_json_str(
        r#"{"steps": [{"select": {"box": {"min": [0,0,0]}}}]}"#,
        "p.json",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("max"), "{e}");
    let e = Plan::from_json_str("{\"steps\": [\n  {\"select\": 3}]}", "p.json")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.json: line 2, column 14") && !e.contains(" at line "),
        "{e}"
    );
    // Columns count characters, not bytes, in JSON as in TOML.
    let e = Plan::from_json_str(
        "{\"name\": \"Kinn-Vorverlagerung ü\", \"steps\": 3}",
        "p.json",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("p.json: line 1, column 44"), "{e}");
    let e = plan_err("[[step]]\nselect = { fragment = \"ü\", fragment = \"b\" }\n");
    assert!(
        e.contains("line 2, column 28") && e.contains("duplicate key `fragment`"),
        "{e}"
    );
}

#[test]
fn plan_cut_errors_name_the_file_the_cut_and_the_problem() {
    let cut = |knife: &str| {
        plan_err(&format!(
            "[[cut]]\nname = \"jaw\"\nknife = {knife}\nside = \"positive\"\n\
             [[step]]\nselect = {{ fragment = \"jaw\" }}\n"
        ))
    };
    for (knife, want) in [
        (
            "{ plane = { point = [0.0, 0.0, 112.0], normal = [0.0, 0.0, 0.0] } }",
            "test.toml: plan cut 1 `jaw`: the plane's normal is zero \
             (knife: plane through (0, 0, 112) with normal (0, 0, 0))",
        ),
        (
            "{ sphere = { center = [1.0, 2.0, 3.0], radius = 0.0 } }",
            "the sphere's radius must be > 0 (knife: sphere centred at (1, 2, 3) with radius 0)",
        ),
        (
            "{ rect = { center = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0], u = [0.0, 0.0, 2.0], half_extents = [1.0, 1.0] } }",
            "the rectangle's normal or u is zero, or they are parallel",
        ),
        (
            "{ rect = { center = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0], u = [1.0, 0.0, 0.0], half_extents = [1.0, -1.0] } }",
            "half extents must be > 0",
        ),
    ] {
        let e = cut(knife);
        assert!(e.contains(want) && !e.contains(" { "), "{e}");
    }
    // A step naming no cut fails before any work is done.
    let plan = Plan::from_toml_str(
        "[[cut]]\nname = \"jaw\"\nknife = { plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] } }\n\
         side = \"positive\"\n[[step]]\nname = \"advance\"\nselect = { fragment = \"chin\" }\n",
        "test.toml",
    )
    .unwrap();
    let e = plan
        .check_fragments(&Fragments::new())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test.toml: plan step 1 `advance`: unknown fragment `chin` (known: [jaw])"),
        "{e}"
    );
    let supplied = Fragments::from([("chin".to_string(), vec![0])]);
    plan.check_fragments(&supplied).unwrap();
}

#[test]
fn plan_errors_name_the_file_and_increments_are_bounded() {
    let e = Plan::from_toml_str(
        "[[step]]\nselect = { vertices = [0] }\nincrements = 4000000000\n",
        "big.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("big.toml") && e.contains("plan step 1") && e.contains("100000"),
        "{e}"
    );
    // Errors speak the plan's language, not Rust's.
    for (text, want) in [
        (
            "iterations = -3",
            "integer `-3`, expected a count of iterations or \"converge\"",
        ),
        (
            "iterations = \"forever\"",
            "string \"forever\", expected a count",
        ),
        (
            "rotate = { axis = [0, 0, 0], degrees = 5, center = [0, 0, 0] }",
            "got axis (0, 0, 0), degrees 5, center (0, 0, 0)",
        ),
    ] {
        let e = Plan::from_toml_str(
            &format!("[[step]]\nselect = {{ vertices = [0] }}\n{text}\n"),
            "p.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains(want) && !e.contains("Repr") && !e.contains('{'),
            "{e}"
        );
    }
}

#[test]
fn plans_parse_from_toml_and_json_alike() {
    let toml = "name = \"t\"\n[[step]]\nselect = { half_space = { point = [0,0,0], normal = [0,1,0] } }\n\
                translate = [0, 0, 1]\nincrements = 4\niterations = 3\nreset_velocities = true\n\
                rotate = { axis = [0, 1, 0], degrees = 10, center = [0, 0, 0] }\n";
    let a = Plan::from_toml_str(toml, "t.toml").unwrap();
    let json = r#"{"name": "t", "steps": [{"select": {"half_space": {"point": [0,0,0], "normal": [0,1,0]}},
        "translate": [0,0,1], "increments": 4, "iterations": 3, "reset_velocities": true,
        "rotate": {"axis": [0,1,0], "degrees": 10, "center": [0,0,0]}}]}"#;
    let b = Plan::from_json_str(json, "t.json").unwrap();
    assert_eq!(
        (a.source.as_deref(), b.source.as_deref()),
        (Some("t.toml"), Some("t.json"))
    );
    assert_eq!(
        Plan {
            source: None,
            ..a.clone()
        },
        Plan { source: None, ..b }
    );
    assert_eq!(a.steps[0].iterations, Iterations::Fixed(3));
    let c = Plan::from_toml_str("[[step]]\nselect = { fragment = \"jaw\" }\n", "c").unwrap();
    assert_eq!(c.steps[0].iterations, Iterations::Converge);
    assert_eq!(c.steps[0].increments, 1);
}

#[test]
fn resolution_checks_the_bone_layer() {
    let net = SpringNetwork::build(&grid(5, 5), None, &NetworkParams::default()).unwrap();
    let resolve = |toml: &str| {
        Plan::from_toml_str(toml, "r.toml")
            .unwrap()
            .resolve(&net, &Fragments::new())
    };
    let e = resolve(
        "[[step]]\nname = \"far\"\nselect = { sphere = { center = [100,0,0], radius = 1 } }\n",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("far") && e.contains("empty selection") && e.contains("bone layer"),
        "{e}"
    );
    let e = resolve("[[step]]\nselect = { vertices = [0, 25] }\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("25") && e.contains("outside the bone layer"),
        "{e}"
    );
    let e = resolve("[[step]]\nselect = { fragment = \"jaw\" }\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown fragment `jaw`"), "{e}");
    let ok = Plan::from_toml_str(
        "[[step]]\nselect = { fragment = \"jaw\" }\ntranslate = [1,0,0]\nincrements = 2\n",
        "ok",
    )
    .unwrap()
    .resolve(&net, &Fragments::from([("jaw".into(), vec![3, 1, 3])]))
    .unwrap();
    assert_eq!(ok.steps[0].bone_vertices, vec![1, 3]);
    let half = ok.steps[0].targets(1);
    let b1 = net.bone_rest()[1];
    assert!((half[0][0] - (b1[0] + 0.5)).abs() < 1e-6);
}

#[test]
fn later_steps_select_on_the_moved_bone() {
    let net = SpringNetwork::build(&grid(5, 5), None, &NetworkParams::default()).unwrap();
    let b0 = net.bone_rest()[0];
    let toml = format!(
        "[[step]]\nselect = {{ vertices = [0] }}\ntranslate = [100, 0, 0]\n\
         [[step]]\nselect = {{ sphere = {{ center = [{}, {}, {}], radius = 0.01 }} }}\n",
        b0[0] + 100.0,
        b0[1],
        b0[2]
    );
    let r = Plan::from_toml_str(&toml, "m")
        .unwrap()
        .resolve(&net, &Fragments::new())
        .unwrap();
    assert_eq!(r.steps[1].bone_vertices, vec![0]);
}

#[test]
fn rotation_increments_are_exact_fractions() {
    let net = SpringNetwork::build(&grid(3, 3), None, &NetworkParams::default()).unwrap();
    let plan = Plan {
        name: None,
        cuts: Vec::new(),
        steps: vec![Step {
            name: None,
            select: Selector::Vertices(vec![8]),
            translate: [0.0; 3],
            rotate: Some(chisel::tissue::Rotation {
                axis: [0.0, 0.0, 1.0],
                degrees: 90.0,
                center: [0.0; 3],
            }),
            increments: 3,
            iterations: Iterations::Fixed(1),
            reset_velocities: false,
        }],
        source: None,
    };
    let r = plan.resolve(&net, &Fragments::new()).unwrap();
    let b = net.bone_rest()[8];
    let end = r.steps[0].targets(3)[0];
    // (x, y) rotated by 90° about z: (−y, x).
    assert!((end[0] + b[1]).abs() < 1e-5 && (end[1] - b[0]).abs() < 1e-5);
    let third = r.steps[0].targets(1)[0];
    let angle = (third[1].atan2(third[0]) - b[1].atan2(b[0])).to_degrees();
    assert!((angle - 30.0).abs() < 1e-3, "{angle}");
}

// ---------------------------------------------------------------- Δt

#[test]
fn unstable_dt_is_refused_unless_forced() {
    let net = SpringNetwork::build(&grid(4, 4), None, &NetworkParams::default()).unwrap();
    let limit = explicit::stability_limit(&net);
    assert!(limit > 0.0 && limit.is_finite());
    assert_eq!(
        explicit::choose_dt(&net, None, false).unwrap(),
        explicit::DEFAULT_FRACTION * limit
    );
    let e = explicit::choose_dt(&net, Some(1.5 * limit), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("stability limit"), "{e}");
    assert_eq!(
        explicit::choose_dt(&net, Some(1.5 * limit), true).unwrap(),
        1.5 * limit
    );
    assert!(explicit::choose_dt(&net, Some(-1.0), true).is_err());
}

// ---------------------------------------------------------------- oracle

/// One free node on a spring to a fixed node: a damped oscillator.
fn single_spring(c: f32, gamma: f32) -> SpringNetwork {
    SpringNetwork::from_parts(
        &[Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[Material::linear(c)],
        1.0,
        gamma,
    )
    .unwrap()
}

#[test]
fn oracle_single_spring_period_and_decay() {
    let (c, gamma) = (4.0f64, 0.2f64);
    let net = single_spring(c as f32, gamma as f32);
    let mut s = OracleState::new(&net, &[DVec3::ZERO]);
    s.x[0].x = 1.1; // 0.1 extension
    let dt = 1e-4;
    let mut crossings = Vec::new();
    let mut peaks = Vec::new();
    let mut prev = s.x[0].x - 1.0;
    let mut prev_v = 0.0;
    for k in 0..200_000 {
        s.step(&net, dt, &[]);
        let u = s.x[0].x - 1.0;
        if prev > 0.0 && u <= 0.0 {
            crossings.push(k as f64 * dt);
        }
        if prev_v > 0.0 && s.v[0].x <= 0.0 {
            peaks.push(u);
        }
        prev = u;
        prev_v = s.v[0].x;
    }
    let omega_d = (c - gamma * gamma / 4.0).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega_d;
    let measured = (crossings[5] - crossings[1]) / 4.0;
    assert!(
        (measured - period).abs() < 1e-3 * period,
        "{measured} vs {period}"
    );
    let decay = peaks[2] / peaks[1];
    let expect = (-gamma / 2.0 * period).exp();
    assert!((decay - expect).abs() < 2e-3, "{decay} vs {expect}");
}

#[test]
fn oracle_chain_reaches_series_spring_equilibrium() {
    // Fixed ends at x = 0 and x = 4 (moved to 5); three free nodes; springs
    // c = 1, 2, 1, 2 in series: equal tension, extension_i = T / c_i.
    let pos: Vec<Vec3> = [1.0, 2.0, 3.0, 0.0, 4.0]
        .iter()
        .map(|&x| Vec3::new(x, 0.0, 0.0))
        .collect();
    let mats = [Material::linear(1.0), Material::linear(2.0)];
    let net = SpringNetwork::from_parts(
        &pos,
        3,
        &[(3, 0, 0), (0, 1, 1), (1, 2, 0), (2, 4, 1)],
        &mats,
        1.0,
        1.0,
    )
    .unwrap();
    let mut s = OracleState::new(&net, &[DVec3::ZERO, DVec3::new(5.0, 0.0, 0.0)]);
    s.settle(&net, 0.1, &[], 1e-12, 1_000_000);
    let tension = 1.0 / (1.0 + 0.5 + 1.0 + 0.5);
    let expect = [1.0 + tension, 2.0 + tension * 1.5, 3.0 + tension * 2.5];
    for (k, (x, want)) in s.x.iter().zip(expect).enumerate() {
        assert!((x.x - want).abs() < 1e-9, "{k}: {} vs {want}", x.x);
    }
    assert!(s.residual(&net, &[]) < 1e-10);
}

#[test]
fn oracle_biphasic_knee() {
    let m = Material {
        c1: 1.0,
        c2: 5.0,
        knee: 0.1,
    };
    assert_eq!(oracle::spring_force(&m, 0.05, 1.0), 0.05);
    assert!((oracle::spring_force(&m, 0.2, 1.0) - (0.1 + 0.5)).abs() < 1e-7);
    // Continuous at the knee, linear in compression.
    assert!((oracle::spring_force(&m, 0.1 + 1e-12, 1.0) - 0.1).abs() < 1e-10);
    assert_eq!(oracle::spring_force(&m, -0.3, 1.0), -0.3);
    // Static load past the knee: extension = knee·l + (f − c1·knee·l)/c2.
    let net = SpringNetwork::from_parts(
        &[Vec3::new(2.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[m],
        1.0,
        1.0,
    )
    .unwrap();
    let f = [DVec3::new(1.2, 0.0, 0.0)];
    let mut s = OracleState::new(&net, &[DVec3::ZERO]);
    s.settle(&net, 0.05, &f, 1e-13, 1_000_000);
    let expect = 2.0 + 0.2 + (1.2 - 0.2) / 5.0;
    assert!((s.x[0].x - expect).abs() < 1e-7, "{}", s.x[0].x);
}

/// The f32 mirror tracks the f64 oracle on a biphasic network with an
/// external load (so the knee is crossed) and a moved bone.
#[test]
fn mirror_tracks_oracle() {
    let mesh = common::icosphere(2);
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let n = mesh.n_vertices();
    let mut bone: Vec<[f32; 4]> = net.bone_rest().to_vec();
    for b in bone.iter_mut().filter(|b| b[1] > 0.4) {
        b[2] += 0.08;
    }
    let forces: Vec<Vec3> = (0..net.n_free)
        .map(|i| {
            if i < n && mesh.positions[i].x > 0.5 {
                Vec3::new(0.3, 0.0, 0.0)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let opts = RelaxOptions {
        external_forces: Some(forces.clone()),
        ..RelaxOptions::default()
    };
    let dt = explicit::choose_dt(&net, None, false).unwrap();
    let iters = 300;
    let mirror = chisel::tissue::iterate(&net, &bone, &opts, iters, Backend::Cpu).unwrap();
    let bone64: Vec<DVec3> = bone
        .iter()
        .map(|b| DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64))
        .collect();
    let f64s: Vec<DVec3> = forces.iter().map(|f| f.as_dvec3()).collect();
    let mut s = OracleState::new(&net, &bone64);
    for _ in 0..iters {
        s.step(&net, dt as f64, &f64s);
    }
    let moved = (0..net.n_free)
        .map(|i| {
            s.x[i].distance(DVec3::new(
                net.rest[i][0] as f64,
                net.rest[i][1] as f64,
                net.rest[i][2] as f64,
            ))
        })
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "the test must move the network ({moved})");
    let worst = (0..net.n_free)
        .map(|i| {
            let m = mirror[i];
            s.x[i].distance(DVec3::new(m[0] as f64, m[1] as f64, m[2] as f64))
        })
        .fold(0.0, f64::max);
    // f32 rounding over 300 iterations of a unit-size network.
    assert!(worst < 1e-4, "mirror vs oracle: {worst}");
    // The dermis knee was crossed somewhere (biphasic law exercised).
    let stretched = net.springs.iter().any(|sp| {
        sp.class == SpringClass::Dermis
            && s.x[sp.a as usize].distance(s.x[sp.b as usize]) > 1.1 * sp.rest as f64
    });
    assert!(stretched);
}

/// `block_solve` inverts the 3 × 3 block: B⁻¹(B x) = x to f32 accuracy for
/// SPD blocks of condition up to ~10³ and any scale (1e-6 to 1e6), and a
/// block of zero trace (a node without springs) gives 0.
#[test]
fn block_solve_inverts_the_preconditioner_block() {
    use chisel::tissue::cpu::block_solve;
    let mut bits = common::xorshift(0x9e37_79b9_7f4a_7c15);
    let mut next = move || (bits() >> 40) as f64 / (1u64 << 24) as f64 - 0.5;
    for case in 0..200 {
        let scale = 10f64.powi(case % 13 - 6);
        // B = Σ_k λ_k e_k e_kᵀ over a random orthonormal frame.
        let a = glam::DVec3::new(next(), next(), next()).normalize();
        let b = a
            .cross(glam::DVec3::new(next(), next(), next()))
            .normalize();
        let c = a.cross(b);
        let lambda = [1.0, 10f64.powf(-3.0 * (next() + 0.5)), 0.05 + next().abs()];
        let m = glam::DMat3::from_cols(a, b, c)
            * glam::DMat3::from_diagonal(glam::DVec3::from_array(lambda) * scale)
            * glam::DMat3::from_cols(a, b, c).transpose();
        let blk = [
            m.x_axis.x, m.y_axis.y, m.z_axis.z, m.y_axis.x, m.z_axis.x, m.z_axis.y,
        ]
        .map(|v| v as f32);
        let x = glam::DVec3::new(next(), next(), next());
        let d = m * x;
        let got = block_solve(blk, [d.x as f32, d.y as f32, d.z as f32]);
        let err = (glam::DVec3::new(got[0] as f64, got[1] as f64, got[2] as f64) - x).length();
        // f32 rounding of B and d, amplified by the condition number.
        let cond = 1.0 / lambda[1].min(lambda[2]);
        assert!(
            err < 1e-5 * cond * x.length(),
            "case {case}: {err} (cond {cond})"
        );
    }
    assert_eq!(block_solve([0.0; 6], [1.0, 2.0, 3.0]), [0.0; 3]);
}

/// The step kernels' fast path equals their mirrors (the plain per-node
/// loops) bit for bit at every gather width this CPU has (detected at run
/// time: 4 everywhere, 8 with AVX2, 16 with AVX-512), for free
/// node counts that fill no whole lane group, rows of 0 to many springs
/// (lanes ending at different k, inside and past the interleaved steps of
/// a wide group), a zero-length spring, three materials (one of them id
/// 15, the last of the table) and external forces.
#[test]
fn fast_path_equals_the_mirror() {
    use chisel::tissue::cpu::fast::{Lanes, SpringGather};
    use chisel::tissue::cpu::{self, SpringChebyshevParams, SpringStepParams};
    let widths: Vec<Lanes> = Lanes::ALL
        .into_iter()
        .filter(|l| l.is_available())
        .collect();
    for l in Lanes::ALL.into_iter().filter(|l| !l.is_available()) {
        eprintln!("this CPU lacks {}: not tested here", l.name());
    }
    let mut bits = common::xorshift(0x2545_f491_4f6c_dd1d);
    let mut next = move || (bits() >> 40) as f32 / (1u64 << 24) as f32;
    let mut materials = vec![Material::linear(0.1); 16];
    materials[0] = Material::linear(1.3);
    materials[1] = Material {
        c1: 0.7,
        c2: 4.0,
        knee: 0.05,
    };
    materials[15] = Material {
        c1: 2.0,
        c2: 0.5,
        knee: 0.02,
    };
    let mut mats = [[0.0f32; 4]; 16];
    for (row, m) in mats.iter_mut().zip(&materials) {
        *row = m.table_row();
    }
    for n_free in [1usize, 2, 3, 5, 6, 7, 9, 13, 16, 17, 24, 31, 40, 53, 70] {
        let n = n_free + 4;
        let mut p: Vec<Vec3> = (0..n).map(|_| Vec3::new(next(), next(), next())).collect();
        // Nodes 0 and 1 coincide: a spring of rest length 0.
        p[1] = p[0];
        let mut springs = vec![(0u32, 1u32, 0u8)];
        for a in 0..n as u32 {
            // Rows of 0 to 4 own springs (plus those of other nodes), and
            // beyond 16 nodes 6 to 9 more (every lane of a wide group has
            // springs, its rows end at different k).
            let own = if n_free > 16 {
                6 + a as usize % 4
            } else {
                a as usize % 5
            };
            for k in 0..own {
                let b = (a as usize + 1 + 2 * k) % n;
                springs.push((a, b as u32, [0, 1, 15][k % 3]));
            }
        }
        springs.retain(|&(a, b, _)| a != b);
        let net = SpringNetwork::from_parts(&p, n_free, &springs, &materials, 1.0, 0.5).unwrap();
        let mut pos: Vec<[f32; 4]> = (0..n)
            .map(|i| {
                let w = if i < n_free { 0.5 + next() } else { 0.0 };
                [
                    0.2 * next() - 0.1,
                    0.2 * next() - 0.1,
                    0.2 * next() - 0.1,
                    w,
                ]
            })
            .collect();
        // ... and keep coinciding: r = 0, which the kernels skip.
        let first = pos[0];
        pos[1][..3].copy_from_slice(&first[..3]);
        let vel: Vec<[f32; 4]> = (0..n_free)
            .map(|_| [next() - 0.5, next() - 0.5, 0.0, 0.0])
            .collect();
        let forces: Vec<[f32; 4]> = (0..n_free)
            .map(|_| [next() - 0.5, 0.0, next(), 0.0])
            .collect();
        for (chebyshev, &lanes) in [false, true]
            .into_iter()
            .flat_map(|c| widths.iter().map(move |l| (c, l)))
        {
            // The parameters of both kernels (their fields by name).
            struct Params {
                dt: f32,
                damping: f32,
                gain: f32,
                isotropy: f32,
            }
            let params = Params {
                dt: 0.05,
                damping: if chebyshev { 0.9 } else { 0.5 },
                gain: 1.7,
                isotropy: 0.1,
            };
            let chebyshev_params = SpringChebyshevParams {
                n_free: n_free as u32,
                use_forces: true,
                h: params.dt,
                momentum: params.damping,
                gain: params.gain,
                isotropy: params.isotropy,
                materials: mats,
            };
            let step_params = SpringStepParams {
                n_free: n_free as u32,
                use_forces: true,
                dt: params.dt,
                damping: params.damping,
                materials: mats,
            };
            // Fast path and mirror from the same inputs; `forces` and
            // `vel` zero: the springs alone (their loading).
            let run = |fast: bool, forces: &[[f32; 4]], vel: &[[f32; 4]]| {
                let (mut out, mut v_out) = (pos.clone(), vel.to_vec());
                let gather = SpringGather::new(&net.csr, n_free, lanes).unwrap();
                assert_eq!(gather.lanes(), lanes);
                let (rest, csr) = (&net.rest, &net.csr);
                match (chebyshev, fast) {
                    (true, true) => gather.spring_chebyshev(
                        &chebyshev_params,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                    (true, false) => cpu::spring_chebyshev(
                        &chebyshev_params,
                        csr,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                    (false, true) => {
                        gather.spring_step(&step_params, rest, forces, &pos, &mut out, &mut v_out)
                    }
                    (false, false) => cpu::spring_step(
                        &step_params,
                        csr,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                }
                (out, v_out)
            };
            let (out, v_out) = run(true, &forces, &vel);
            let (m_out, m_vel) = run(false, &forces, &vel);
            for i in 0..n {
                let what = format!(
                    "{}: n_free {n_free}, chebyshev {chebyshev}, node {i}",
                    lanes.name()
                );
                assert_eq!(
                    out[i].map(f32::to_bits),
                    m_out[i].map(f32::to_bits),
                    "position: {what}"
                );
                if i < n_free {
                    assert_eq!(
                        v_out[i].map(f32::to_bits),
                        m_vel[i].map(f32::to_bits),
                        "velocity: {what}"
                    );
                }
            }
            let zero = vec![[0.0f32; 4]; n_free];
            let loaded = run(false, &zero, &zero)
                .1
                .iter()
                .any(|v| v[..3] != [0.0; 3]);
            assert!(loaded, "the springs must be loaded");
            // Only the free nodes are written.
            assert_eq!(&out[n_free..], &pos[n_free..]);
        }
    }
}

// ---------------------------------------------------------------- stop criteria

fn one_step_plan(
    net: &SpringNetwork,
    dx: f32,
    increments: u32,
    iterations: Iterations,
) -> chisel::tissue::ResolvedPlan {
    Plan {
        name: None,
        cuts: Vec::new(),
        steps: vec![Step {
            name: Some("move".into()),
            select: Selector::Vertices((0..net.n_bone() as u32).step_by(3).collect()),
            translate: [dx, 0.0, 0.0],
            rotate: None,
            increments,
            iterations,
            reset_velocities: false,
        }],
        source: None,
    }
    .resolve(net, &Fragments::new())
    .unwrap()
}

#[test]
fn stop_criteria_converged_stalled_diverged_limit() {
    let mesh = common::icosphere(1);
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 2, Iterations::Converge);
    let r = relax(&net, &plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Converged);
    assert!(
        r.steps[0]
            .increments
            .iter()
            .all(|i| i.max_speed < r.epsilon)
    );
    assert!(r.iterations > 0 && r.iterations.is_multiple_of(25));
    assert!(r.max_displacement > 0.0);

    let limited = RelaxOptions {
        max_iterations: 30,
        epsilon: Some(1e-12),
        ..RelaxOptions::default()
    };
    let r = relax(&net, &plan, &limited, Backend::Cpu).unwrap();
    assert_eq!(r.steps[0].increments[0].status, Status::IterationLimit);
    assert_eq!(r.steps[0].increments[0].iterations, 30);

    // Undamped oscillation with a generous δ: stalled at the first window.
    let osc = SpringNetwork::from_parts(
        &[Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[Material::linear(1.0)],
        1.0,
        0.0,
    )
    .unwrap();
    let plan = Plan::from_toml_str(
        "[[step]]\nselect = { vertices = [0] }\ntranslate = [0.5, 0, 0]\n",
        "o",
    )
    .unwrap()
    .resolve(&osc, &Fragments::new())
    .unwrap();
    let stall = RelaxOptions {
        delta: Some(10.0),
        epsilon: Some(1e-9),
        ..RelaxOptions::default()
    };
    let r = relax(&osc, &plan, &stall, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Stalled);
    assert_eq!(r.iterations, 100);
    assert!(r.steps[0].increments[0].window_change.unwrap() < 10.0);

    // Forced Δt far above the limit: diverged, and the plan stops there.
    let limit = explicit::stability_limit(&net);
    let wild = RelaxOptions {
        dt: Some(3.0 * limit),
        force_dt: true,
        ..RelaxOptions::default()
    };
    let plan = one_step_plan(&net, 0.05, 4, Iterations::Converge);
    let r = relax(&net, &plan, &wild, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Diverged);
    assert_eq!(
        r.steps[0].increments.len(),
        1,
        "plan must stop at divergence"
    );
}

#[test]
fn fixed_iteration_increments_and_velocity_reset() {
    let net = SpringNetwork::build(&common::icosphere(1), None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 10, Iterations::Fixed(1));
    let carry = relax(&net, &plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(carry.iterations, 10);
    assert_eq!(carry.steps[0].increments.len(), 10);
    let mut reset_plan = plan.clone();
    reset_plan.steps[0].reset_velocities = true;
    let reset = relax(&net, &reset_plan, &RelaxOptions::default(), Backend::Cpu).unwrap();
    // With one iteration per increment and zeroed velocities the network
    // can only creep: it moves strictly less than when momentum carries.
    assert!(reset.max_displacement < carry.max_displacement);
    assert!(reset.max_displacement > 0.0);
}

// ---------------------------------------------------------------- accelerated solver

/// Relaxes `plan` with both solvers to a tight ε and returns (max distance
/// between the equilibria, largest displacement, explicit iterations,
/// chebyshev iterations).
fn compare_solvers(
    net: &SpringNetwork,
    plan: &chisel::tissue::ResolvedPlan,
    eps: f32,
) -> (f32, f32, u64, u64) {
    let opts = |solver| RelaxOptions {
        solver,
        epsilon: Some(eps),
        max_iterations: 1_000_000,
        ..RelaxOptions::default()
    };
    let a = relax(net, plan, &opts(Solver::Explicit), Backend::Cpu).unwrap();
    let b = relax(net, plan, &opts(Solver::Chebyshev), Backend::Cpu).unwrap();
    let per_inc = |r: &chisel::tissue::RelaxReport| {
        r.steps[0]
            .increments
            .iter()
            .map(|i| i.iterations)
            .collect::<Vec<_>>()
    };
    eprintln!("explicit {:?}\nchebyshev {:?}", per_inc(&a), per_inc(&b));
    // Stalled = at rest within the f32 noise floor of the positions.
    for r in [&a, &b] {
        assert!(
            matches!(r.status, Status::Converged | Status::Stalled),
            "{:?}",
            r.status
        );
    }
    let dist = (0..net.n_free)
        .map(|i| {
            let (p, q) = (a.positions[i], b.positions[i]);
            Vec3::new(p[0] - q[0], p[1] - q[1], p[2] - q[2]).length()
        })
        .fold(0.0, f32::max);
    let disp = (0..net.n_free)
        .map(|i| {
            let (p, r) = (a.positions[i], net.rest[i]);
            Vec3::new(p[0] - r[0], p[1] - r[1], p[2] - r[2]).length()
        })
        .fold(0.0, f32::max);
    (dist, disp, a.iterations, b.iterations)
}

#[test]
fn chebyshev_reaches_the_explicit_equilibrium_on_a_sphere() {
    let net = SpringNetwork::build(&common::icosphere(3), None, &NetworkParams::default()).unwrap();
    let plan = one_step_plan(&net, 0.05, 1, Iterations::Converge);
    let (dist, disp, it_e, it_c) = compare_solvers(&net, &plan, 1e-6);
    eprintln!("icosphere(3): dist {dist:e}, disp {disp:e}, explicit {it_e}, chebyshev {it_c}");
    assert!(disp > 0.01);
    assert!(dist < 1e-3 * disp, "{dist} vs {disp}");
    assert!(it_c < it_e);
}

#[test]
fn chebyshev_reaches_the_explicit_equilibrium_on_fran_cut() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    let plan = Plan::from_toml_str(phantom::FRAN_CHIN_ADVANCE_TOML, "chin")
        .unwrap()
        .resolve(&net, &Fragments::new())
        .unwrap();
    // ε = 3e-7 m/s is just above the f32 noise floor of 0.1 m coordinates.
    let (dist, disp, it_e, it_c) = compare_solvers(&net, &plan, 3e-7);
    eprintln!("fran_cut: dist {dist:e}, disp {disp:e}, explicit {it_e}, chebyshev {it_c}");
    assert!(disp > 0.002, "{disp}");
    assert!(dist < 2.5e-3 * disp, "{dist} vs {disp}");
    assert!(it_c < it_e);
}

/// On fran_cut's network (real data) with the bone advanced 2 mm, every
/// gather width this CPU has gives the mirror's bits through 30 iterations
/// of each solver (the interleaved rows of 8 and 16 nodes, the tails past
/// them and the four-lane rest of each rayon task all take part).
#[test]
fn fast_path_equals_the_mirror_on_fran_cut() {
    use chisel::tissue::chebyshev::BLOCK_ISOTROPY;
    use chisel::tissue::cpu::fast::{Lanes, SpringGather};
    use chisel::tissue::cpu::{self, SpringChebyshevParams, SpringStepParams};
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    let nf = net.n_free;
    let mut mats = [[0.0f32; 4]; 16];
    for (row, m) in mats.iter_mut().zip(&net.materials) {
        *row = m.table_row();
    }
    let mut start = vec![[0.0f32, 0.0, 0.0, 1.0 / net.params.mass]; net.n_nodes()];
    for u in &mut start[nf..] {
        *u = [0.0, 0.002, 0.001, 0.0];
    }
    let widths: Vec<Lanes> = Lanes::ALL
        .into_iter()
        .filter(|l| l.is_available())
        .collect();
    let dt = explicit::choose_dt(&net, None, false).unwrap();
    let step = SpringStepParams {
        n_free: nf as u32,
        use_forces: false,
        dt,
        damping: net.params.damping,
        materials: mats,
    };
    let chebyshev_params = SpringChebyshevParams {
        n_free: nf as u32,
        use_forces: false,
        h: dt,
        momentum: 0.9,
        gain: 0.5,
        isotropy: BLOCK_ISOTROPY,
        materials: mats,
    };
    for chebyshev in [false, true] {
        let states: Vec<_> = widths
            .iter()
            .map(|&lanes| {
                let gather = SpringGather::new(&net.csr, nf, lanes).unwrap();
                let (mut a, mut b) = (start.clone(), start.clone());
                let mut vel = vec![[0.0f32; 4]; nf];
                for _ in 0..30 {
                    if chebyshev {
                        gather.spring_chebyshev(
                            &chebyshev_params,
                            &net.rest,
                            &[],
                            &a,
                            &mut b,
                            &mut vel,
                        );
                    } else {
                        gather.spring_step(&step, &net.rest, &[], &a, &mut b, &mut vel);
                    }
                    std::mem::swap(&mut a, &mut b);
                }
                (a, vel)
            })
            .collect();
        let mirror = {
            let (mut a, mut b) = (start.clone(), start.clone());
            let mut vel = vec![[0.0f32; 4]; nf];
            for _ in 0..30 {
                if chebyshev {
                    let p = &chebyshev_params;
                    cpu::spring_chebyshev(p, &net.csr, &net.rest, &[], &a, &mut b, &mut vel);
                } else {
                    cpu::spring_step(&step, &net.csr, &net.rest, &[], &a, &mut b, &mut vel);
                }
                std::mem::swap(&mut a, &mut b);
            }
            (a, vel)
        };
        let moved = states[0].0[..nf]
            .iter()
            .filter(|u| u[..3] != [0.0; 3])
            .count();
        assert!(
            moved > nf / 4,
            "the bone move must load the network: {moved} of {nf} moved"
        );
        for (lanes, (u, v)) in widths.iter().zip(&states) {
            let bits = |x: &[[f32; 4]]| x.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(u) == bits(&mirror.0) && bits(v) == bits(&mirror.1),
                "{} differs from the mirror (chebyshev {chebyshev})",
                lanes.name(),
            );
        }
    }
}

#[test]
fn fran_cut_network_and_seed_plans() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    // SPEC default origin: back face (x = 0) of the bounding box, mid y/z.
    assert!(net.origin.x.abs() < 1e-6, "{}", net.origin);
    assert!((net.origin.y + 0.128).abs() < 1e-4 && (net.origin.z + 0.0574).abs() < 1e-4);
    // 6,615 nodes; 42,978 springs with a free end (43k as in the issue).
    assert_eq!(net.n_nodes(), 6615);
    let c = net.class_counts();
    assert_eq!(c[0] + c[1] + c[2] + c[3], 6428 + 15061 + 6428 + 15061);
    let plan = Plan::from_toml_str(phantom::FRAN_TABLE2_TOML, "table2").unwrap();
    let r = plan.resolve(&net, &Fragments::new()).unwrap();
    let counts: Vec<usize> = r.steps.iter().map(|s| s.bone_vertices.len()).collect();
    for (got, want) in counts.iter().zip([60, 60, 150, 70]) {
        assert!(got.abs_diff(want) * 10 <= want, "{counts:?}");
    }
    let report = relax(&net, &r, &RelaxOptions::default(), Backend::Cpu).unwrap();
    assert_eq!(report.iterations, 10 + 10 + 8 + 5);
    assert_ne!(report.status, Status::Diverged);
    let skin = report.skin_mesh(&net);
    assert_eq!(skin.n_vertices(), 2205);
    assert!(
        skin.scalar("displacement")
            .unwrap()
            .values
            .iter()
            .any(|&d| d > 1e-4)
    );
}

#[test]
fn refined_fran_cut_sizes_match_the_benchmark_networks() {
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let (cols, rows) = FRAN_GRID;
    let fine = phantom::refine_grid(&face, cols, rows, 4).unwrap();
    assert_eq!(fine.n_vertices(), 177 * 193);
    // Same orientation as the input (inward), same bounds.
    let (lo, hi) = fine.bounds().unwrap();
    let (lo0, hi0) = face.bounds().unwrap();
    assert!((lo - lo0).abs().max_element() < 1e-3 && (hi - hi0).abs().max_element() < 1e-3);
}
