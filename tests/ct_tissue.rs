//! CT → tissue (issue: marching cubes, cutting and the CT-to-tissue
//! pipeline): layers from a CT by marching cubes, plan `[[cut]]` bone
//! fragments, the subcutis between skin and a real bone, and a relaxation
//! that moves a cut-free jaw — on the generated CT phantom and on headsq.

mod common;

use std::collections::HashMap;

use chisel::Backend;
use chisel::tissue::CtParams;
use chisel::tissue::ct::CT_SUBCUTIS_DEPTH;
use chisel::tissue::phantom::{self, HEADSQ_CHIN_ADVANCE_TOML, ct_demo_plan, ct_head_phantom};
use chisel::tissue::{
    CtLayers, NetworkParams, Plan, RelaxOptions, Solver, SpringNetwork, Status, cut_bone,
    layers_from_ct, relax,
};
use chisel::{TriMesh, Volume};
use glam::Vec3;

fn phantom_layers(voxel: f32) -> (Volume, CtLayers) {
    let volume = ct_head_phantom(voxel).unwrap();
    let params = CtParams::for_volume(&volume, 500.0, 1150.0);
    let layers = layers_from_ct(&volume, &params, Backend::Cpu).unwrap();
    (volume, layers)
}

/// Every undirected edge used by exactly two triangles, once each way.
fn assert_closed_oriented(mesh: &TriMesh, what: &str) {
    let mut uses: HashMap<(u32, u32), (u32, i32)> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let e = uses.entry((a.min(b), a.max(b))).or_default();
            e.0 += 1;
            e.1 += if a < b { 1 } else { -1 };
        }
    }
    let open = uses.values().filter(|u| u.0 != 2).count();
    let misoriented = uses.values().filter(|u| u.0 == 2 && u.1 != 0).count();
    assert_eq!(open, 0, "{what}: {open} edges not used twice");
    assert_eq!(
        misoriented, 0,
        "{what}: {misoriented} edges used twice one way"
    );
}

fn volume_of(mesh: &TriMesh) -> f64 {
    phantom::signed_volume(mesh)
}

#[test]
fn plan_cuts_parse_and_are_validated() {
    let plan = ct_demo_plan().unwrap();
    assert_eq!(plan.cuts.len(), 1);
    assert_eq!(plan.cuts[0].name, "jaw");
    assert!(plan.cuts[0].cap);
    let json = r#"{"cuts": [{"name": "a", "knife": {"sphere": {"center": [0, 0, 0], "radius": 2}},
        "side": "negative", "cap": false}], "steps": [{"select": {"fragment": "a"}}]}"#;
    let p = Plan::from_json_str(json, "j").unwrap();
    assert!(!p.cuts[0].cap);

    let step = "\n[[step]]\nselect = { fragment = \"a\" }\n";
    let err = |cut: &str| -> String {
        Plan::from_toml_str(&format!("{cut}{step}"), "bad.toml")
            .unwrap_err()
            .to_string()
    };
    let plane = "knife = { plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 1.0, 0.0] } }";
    let e = err(&format!(
        "[[cut]]\nname = \"a\"\n{plane}\nside = \"positive\"\n[[cut]]\nname = \"a\"\n{plane}\nside = \"negative\"\n"
    ));
    assert!(e.contains("used by an earlier cut"), "{e}");
    let e = err(
        "[[cut]]\nname = \"a\"\nknife = { plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 0.0] } }\nside = \"positive\"\n",
    );
    assert!(
        e.contains("bad.toml: plan cut 1 `a`: knife = plane through (0, 0, 0) with normal (0, 0, 0): the plane's normal is zero"),
        "{e}"
    );
    let e = err(&format!(
        "[[cut]]\nname = \"a\"\n{plane}\nside = \"positive\"\nwithin = {{ vertices = [1] }}\n"
    ));
    assert!(
        e.contains("within = 1 vertex ids: takes a sphere, box or half_space"),
        "{e}"
    );
    let e = err(&format!(
        "[[cut]]\nname = \"a\"\n{plane}\nside = \"above\"\n"
    ));
    assert!(e.contains("bad.toml") && e.contains("line"), "{e}");
    let e = err(&format!(
        "[[cut]]\nname = \"a\"\n{plane}\nside = \"positive\"\nblade = 3\n"
    ));
    assert!(e.contains("blade"), "{e}");
    let e = err(
        "[[cut]]\nname = \" \"\nknife = { sphere = { center = [0.0, 0.0, 0.0], radius = 1.0 } }\nside = \"negative\"\n",
    );
    assert!(e.contains("name = \"\": must not be empty"), "{e}");
}

#[test]
fn ct_phantom_layers_by_marching_cubes() {
    let (volume, layers) = phantom_layers(5.0);
    let f = &layers.figures;
    assert_eq!(f.skin_groups, 1, "one closed skin");
    assert_eq!(f.skin_boundary_edges, 0);
    assert_closed_oriented(&layers.skin, "phantom skin");
    // Cranium outer + inner surface; mandible and spine fused to the outer.
    assert_eq!(f.bone_groups, 2);
    assert!(volume_of(&layers.skin) > 0.0 && volume_of(&layers.bone) > 0.0);
    assert!(volume_of(&layers.skin) > 2.0 * volume_of(&layers.bone));
    // Bad levels are refused.
    let levels = |skin, bone| CtParams::for_volume(&volume, skin, bone);
    let e = layers_from_ct(&volume, &levels(1150.0, 500.0), Backend::Cpu).unwrap_err();
    assert!(e.to_string().contains("skin < bone"), "{e}");
    let negative = CtParams {
        skin_min_edge: -1.0,
        ..levels(500.0, 1150.0)
    };
    let e = layers_from_ct(&volume, &negative, Backend::Cpu).unwrap_err();
    assert!(
        matches!(&e, chisel::Error::InvalidParameter { name, .. } if name == "skin_min_edge"),
        "{e}"
    );
    let e = layers_from_ct(&volume, &levels(500.0, 9000.0), Backend::Cpu).unwrap_err();
    assert!(
        e.to_string().contains("no surface at the bone level"),
        "{e}"
    );
    for voxel in [0.5, f32::NAN] {
        assert!(matches!(
            ct_head_phantom(voxel),
            Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "voxel"
        ));
    }
}

#[test]
fn plan_cut_frees_the_phantom_jaw_as_a_closed_piece() {
    let (_, layers) = phantom_layers(5.0);
    let plan = ct_demo_plan().unwrap();
    let cut = cut_bone(&layers.bone, &plan.cuts, None).unwrap();
    let jaw = &cut.fragments["jaw"];
    let jaw_pieces: Vec<_> = cut
        .pieces
        .iter()
        .filter(|p| p.fragments == ["jaw"])
        .collect();
    assert_eq!(jaw_pieces.len(), 1, "{:?}", cut.pieces);
    assert_eq!(jaw.len(), jaw_pieces[0].vertices as usize);
    // Below the osteotomy plane y = −50, in front of the spine.
    for &v in jaw {
        let p = cut.mesh.positions[v as usize];
        assert!(p.y <= -50.0 + 1e-3, "jaw vertex {v} at {p}");
    }
    assert!(jaw_pieces[0].centroid[2] > 0.0);
    // The spine piece below the plane stays behind (`within`).
    assert!(
        cut.pieces
            .iter()
            .any(|p| p.fragments.is_empty() && p.centroid[1] < -50.0 && p.centroid[2] < 0.0)
    );
    // Capped: the two rami and the spine give three closed loops; every
    // piece is closed and volumes add up.
    assert_eq!(cut.stats[0].loops_capped, 3, "{:?}", cut.stats[0]);
    assert_eq!(cut.stats[0].curves_open, 0);
    assert_closed_oriented(&cut.mesh, "cut bone");
    let before = volume_of(&layers.bone);
    let after = volume_of(&cut.mesh);
    assert!(
        ((after - before) / before).abs() < 1e-6,
        "{before} vs {after}"
    );
    // The per-vertex `fragment` field marks the jaw.
    let field = cut.mesh.scalar("fragment").unwrap();
    assert_eq!(
        field.values.iter().filter(|&&v| v == 1.0).count(),
        jaw.len()
    );

    // Negative control: a knife that leaves nothing on the chosen side.
    let mut missing = plan.cuts.clone();
    missing[0].knife = chisel::tissue::KnifeSpec::Plane {
        point: [0.0, -500.0, 0.0],
        normal: [0.0, -1.0, 0.0],
    };
    let e = cut_bone(&layers.bone, &missing, Some("chin.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("chin.toml: plan cut 1 `jaw`: empty selection: no bone piece on the positive side of the plane through (0, -500, 0) with normal (0, -1, 0) has its centroid in the box from"), "{e}");
}

#[test]
fn subcutis_lies_between_skin_and_bone_along_the_normal() {
    let (_, layers) = phantom_layers(6.0);
    let params = NetworkParams {
        subcutis_depth: Some(CT_SUBCUTIS_DEPTH),
        ..Default::default()
    };
    let net = SpringNetwork::build(&layers.skin, Some(&layers.bone), &params).unwrap();
    let n = layers.skin.n_vertices();
    let bone: Vec<Vec3> = layers.bone.positions.clone();
    let nearest = |p: Vec3| {
        bone.iter()
            .map(|b| b.distance(p))
            .fold(f32::INFINITY, f32::min)
    };
    for i in (0..n).step_by(37) {
        let p = layers.skin.positions[i];
        let q = Vec3::from_slice(&net.rest[n + i][..3]);
        let d = nearest(p);
        // |q − p| = depth · dist(p, bone), so no bone vertex is nearer to
        // q than (1 − depth) · dist(p, bone): q is off the bone.
        assert!(
            (p.distance(q) - CT_SUBCUTIS_DEPTH * d).abs() < 1e-3 * d.max(1.0),
            "vertex {i}"
        );
        assert!(
            nearest(q) >= (1.0 - CT_SUBCUTIS_DEPTH) * d - 1e-3,
            "vertex {i}: subcutis at {q} is {} from the bone, skin {d}",
            nearest(q)
        );
    }
    // Without a bone mesh, or outside (0, 1), the placement is refused.
    let e = SpringNetwork::build(&layers.skin, None, &params).unwrap_err();
    assert!(e.to_string().contains("needs a bone mesh"), "{e}");
    let bad = NetworkParams {
        subcutis_depth: Some(1.0),
        ..Default::default()
    };
    assert!(matches!(
        SpringNetwork::build(&layers.skin, Some(&layers.bone), &bad),
        Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "subcutis_depth"
    ));
}

#[test]
fn jaw_advance_moves_the_fragment_and_the_chin_skin() {
    let (_, layers) = phantom_layers(6.0);
    let mut plan = ct_demo_plan().unwrap();
    let cut = cut_bone(&layers.bone, &plan.cuts, None).unwrap();
    let params = NetworkParams {
        subcutis_depth: Some(CT_SUBCUTIS_DEPTH),
        ..Default::default()
    };
    let net = SpringNetwork::build(&layers.skin, Some(&cut.mesh), &params).unwrap();
    plan.steps[0].increments = 2;
    let resolved = plan.resolve(&net, &cut.fragments).unwrap();
    let opts = RelaxOptions {
        solver: Solver::Chebyshev,
        ..RelaxOptions::default()
    };
    let r = relax(&net, &resolved, &opts, Backend::Cpu).unwrap();
    assert_eq!(r.status, Status::Converged);
    let n = layers.skin.n_vertices();
    // Fragment nodes moved by exactly (0, 0, 6); other bone did not move.
    let jaw: std::collections::HashSet<u32> = cut.fragments["jaw"].iter().copied().collect();
    for (k, p) in cut.mesh.positions.iter().enumerate() {
        let moved = Vec3::from_slice(&r.positions[2 * n + k][..3]) - *p;
        let want = if jaw.contains(&(k as u32)) {
            Vec3::new(0.0, 0.0, 6.0)
        } else {
            Vec3::ZERO
        };
        assert!(moved.distance(want) < 1e-4, "bone vertex {k} moved {moved}");
    }
    // The skin over the chin follows most of the way; the crown stays.
    let skin = |sel: &dyn Fn(Vec3) -> bool| -> f32 {
        let (sum, count) = layers
            .skin
            .positions
            .iter()
            .zip(&r.displacement)
            .filter(|(p, _)| sel(**p))
            .fold((0.0, 0), |(s, c), (_, d)| (s + d, c + 1));
        assert!(count > 0);
        sum / count as f32
    };
    let chin = skin(&|p| p.y < -75.0 && p.y > -90.0 && p.z > 50.0);
    let crown = skin(&|p| p.y > 90.0);
    let nape = skin(&|p| p.y < -90.0 && p.z < -40.0);
    assert!(chin > 3.0 && chin < 7.0, "chin skin moved {chin} mm");
    assert!(crown < 0.05 && nape < 0.5, "crown {crown}, nape {nape}");
}

#[test]
fn headsq_layers_and_chin_fragment() {
    let Some(volume) = common::real_volume("headsq/quarter.nhdr") else {
        return;
    };
    let params = CtParams::for_volume(&volume, 500.0, 1150.0);
    assert_eq!(params.skin_min_edge, 0.6 * 3.2);
    let layers = layers_from_ct(&volume, &params, Backend::Cpu).unwrap();
    let f = &layers.figures;
    // The skin at 500: 26 groups, the outer skin the largest (open where
    // the head leaves the volume at the top and the neck); its edges below
    // 1.92 mm collapsed, the few refused ones counted.
    assert_eq!(f.skin_groups, 26);
    assert!(f.skin_boundary_edges > 0);
    let c = &f.skin_collapse;
    assert_eq!(c.vertices_before, 27_752);
    assert_eq!(f.skin_vertices, c.vertices_before - c.collapsed_edges);
    assert!(f.skin_vertices < 12_000, "{}", f.skin_vertices);
    assert!(c.short_edges_left < 400 && c.crossing_pairs == 0, "{c:?}");
    assert!(c.shortest_before < 0.01 && c.shortest_after > 0.01, "{c:?}");
    assert_eq!(f.bone_groups, 76);
    let plan = Plan::from_toml_str(HEADSQ_CHIN_ADVANCE_TOML, "headsq").unwrap();
    let cut = cut_bone(&layers.bone, &plan.cuts, None).unwrap();
    let chin: Vec<_> = cut
        .pieces
        .iter()
        .filter(|p| p.fragments == ["chin"])
        .collect();
    // The lower mandible, and a few specks of bone (tooth roots) in its box.
    let piece = *chin.iter().max_by_key(|p| p.vertices).unwrap();
    let specks: u32 = chin.iter().map(|p| p.vertices).sum::<u32>() - piece.vertices;
    assert!(
        piece.vertices > 1000 && specks * 10 < piece.vertices,
        "{chin:?}"
    );
    let verts = &cut.mesh.positions
        [piece.first_vertex as usize..(piece.first_vertex + piece.vertices) as usize];
    let (lo, hi) = verts.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    // The lower arch of the mandible: both sides, anterior, below the cut.
    assert!(lo.x < 70.0 && hi.x > 130.0, "{lo} {hi}");
    assert!(lo.y > 40.0 && hi.y < 100.0, "{lo} {hi}");
    assert!(lo.z >= 112.0 - 1e-3 && hi.z < 138.0, "{lo} {hi}");
    let vertices = piece.first_vertex..piece.first_vertex + piece.vertices;
    let sub = TriMesh {
        positions: verts.to_vec(),
        triangles: cut
            .mesh
            .triangles
            .iter()
            .filter(|t| vertices.contains(&t[0]))
            .map(|t| t.map(|v| v - piece.first_vertex))
            .collect(),
        scalars: Vec::new(),
    };
    assert_closed_oriented(&sub, "headsq chin fragment");
    assert!(volume_of(&sub) > 10_000.0, "{} mm³", volume_of(&sub));
}
