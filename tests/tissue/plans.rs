//! Plans: validation and its messages, TOML/JSON parsing, resolution
//! against the bone layer, rotation increments, and the Δt policy.

use super::*;

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
    assert!(e.contains("increments = 0"), "{e}");
    let e = plan_err("[[step]]\nselect = { vertices = [1] }\ntranslate = [nan, 0, 0]\n");
    assert!(e.contains("translate = (NaN, 0, 0): must be finite"), "{e}");
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
            "test.toml: plan cut 1 `jaw`: knife = plane through (0, 0, 112) with normal \
             (0, 0, 0): the plane's normal is zero",
        ),
        (
            "{ sphere = { center = [1.0, 2.0, 3.0], radius = 0.0 } }",
            "knife = sphere centred at (1, 2, 3) with radius 0: the sphere's radius must be > 0",
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
    let e = plan.check_fragments(&Fragments::new()).unwrap_err();
    assert!(
        matches!(e.root(), chisel::Error::Unknown { kind: "fragment", name, known }
            if name == "chin" && known == &["jaw"]),
        "{e}"
    );
    let e = e.to_string();
    assert!(
        e.contains("test.toml: plan step 1 `advance`: unknown fragment `chin`; known: [jaw]"),
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
            "rotate = axis (0, 0, 0), degrees 5, center (0, 0, 0): needs a finite",
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
        dynamics: Default::default(),
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
    assert!(matches!(
        explicit::choose_dt(&net, Some(-1.0), true),
        Err(chisel::Error::InvalidParameter { ref name, .. }) if name == "dt"
    ));
}

#[test]
fn dynamics_come_from_the_plan_and_the_command_line_overrides_them() {
    use chisel::tissue::Dynamics;
    let plan = Plan::from_toml_str(
        "[dynamics]\nmass = 2.0\ndamping = 0.25\nwindow = 50\n[[step]]\nselect = { vertices = [1] }\n",
        "d.toml",
    )
    .unwrap();
    assert_eq!(plan.dynamics.mass, Some(2.0));
    let d = plan.dynamics.overridden_by(&Dynamics {
        damping: Some(0.75),
        ..Default::default()
    });
    assert_eq!(
        (d.mass, d.damping, d.window),
        (Some(2.0), Some(0.75), Some(50))
    );
    let mut params = NetworkParams::default();
    d.apply_to_network(&mut params);
    assert_eq!((params.mass, params.damping), (2.0, 0.75));
    let mut opts = RelaxOptions::default();
    d.apply_to_options(&mut opts);
    assert_eq!(opts.window, 50);
    assert_eq!(opts.check_every, RelaxOptions::default().check_every);
    assert_eq!(opts.dt, None);
    // The dynamics reach the network and the report.
    let net = SpringNetwork::build(&grid(3, 3), None, &params).unwrap();
    let resolved = plan.resolve(&net, &Default::default()).unwrap();
    let r = chisel::tissue::relax(&net, &resolved, &opts, chisel::Backend::Cpu).unwrap();
    assert_eq!((r.mass, r.damping, r.window), (2.0, 0.75, 50));
    assert_eq!(r.max_iterations, opts.max_iterations);
    // An unknown key is refused with its name.
    let e = plan_err("[dynamics]\nstiffness = 3\n[[step]]\nselect = { vertices = [1] }\n");
    assert!(e.contains("stiffness") && e.contains("line 2"), "{e}");
}
