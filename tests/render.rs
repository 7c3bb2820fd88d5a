//! Headless previews (`chisel::render`): geometry of the framing, shading,
//! winding invariance, wireframe, colour map + legend, layout and errors,
//! on synthetic meshes and the real data.

mod common;

use chisel::mesh::ScalarField;
use chisel::render::{
    CAPTION_HEIGHT, Facing, Image, Panel, RenderOptions, TITLE_HEIGHT, View, render_image,
    render_panels, render_png,
};
use chisel::{Error, Position, TriMesh};
use glam::Vec3;

/// Rows above this are left alone by pixel checks: the view caption sits there.
const CAPTION_BAND: u32 = CAPTION_HEIGHT;

fn is_background(p: [u8; 4]) -> bool {
    p[..3] == [255, 255, 255]
}

fn luma(p: [u8; 4]) -> f32 {
    0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2])
}

fn opts(size: u32, views: &[View]) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        views: views.to_vec(),
        facing: Facing::Axes,
        ..Default::default()
    }
}

/// Centre `(x, y)` and radius in pixels of the unit sphere's disc in a
/// square `size`-pixel view: views of at least 4 caption bands keep the
/// band free, and the camera fits the bounding sphere plus an 8 % margin
/// to the area below it.
fn disc(size: u32) -> (f32, f32, f32) {
    let band = if size >= 4 * CAPTION_HEIGHT {
        CAPTION_HEIGHT
    } else {
        0
    };
    let area = (size - band) as f32;
    (
        size as f32 / 2.0,
        band as f32 + area / 2.0,
        0.5 * area / 1.08,
    )
}

fn max_channel_diff(a: &Image, b: &Image) -> u8 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.rgba
        .iter()
        .zip(&b.rgba)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// The upper half (y ≥ 0) of an icosphere: an open cap wound outward.
fn hemisphere(n: u32) -> TriMesh {
    let s = common::icosphere(n);
    let tris = s
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&i| s.positions[i as usize].y >= -1e-6))
        .collect();
    TriMesh::new(s.positions, tris).unwrap()
}

fn with_field(mut m: TriMesh, name: &str, f: impl Fn(Vec3) -> f32) -> TriMesh {
    let values = m.positions.iter().map(|&p| f(p)).collect();
    m.scalars.push(ScalarField {
        name: name.into(),
        values,
    });
    m
}

#[test]
fn sphere_fills_its_disc_and_nothing_else() {
    let Some(gpu) = common::gpu() else { return };
    let size = 128;
    let img = render_image(gpu, &common::icosphere(3), &opts(size, &[View::Front])).unwrap();
    assert_eq!((img.width, img.height), (size, size));
    let (cx, cy, r) = disc(size);
    let (mut inside, mut outside) = (0, 0);
    for y in CAPTION_BAND..size {
        for x in 0..size {
            let d = ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt();
            let bg = is_background(img.pixel(x, y));
            if d < 0.97 * r {
                assert!(
                    !bg,
                    "background at ({x}, {y}) inside the disc (d = {d}, r = {r})"
                );
                inside += 1;
            } else if d > 1.02 * r + 1.0 {
                assert!(bg, "{:?} at ({x}, {y}) outside the disc", img.pixel(x, y));
                outside += 1;
            }
        }
    }
    assert!(inside > 5000 && outside > 2000, "{inside} / {outside}");
    // The caption band holds only the caption: the mesh stays below it.
    for x in 100..size {
        for y in 0..CAPTION_BAND {
            assert!(
                is_background(img.pixel(x, y)),
                "({x}, {y}) in the caption band"
            );
        }
    }
}

#[test]
fn front_lit_sphere_is_brightest_in_the_middle() {
    let Some(gpu) = common::gpu() else { return };
    let size = 128;
    let img = render_image(gpu, &common::icosphere(3), &opts(size, &[View::Front])).unwrap();
    let (cx, cy, r) = disc(size);
    let centre = luma(img.pixel(cx as u32, cy as u32));
    for k in 0..8 {
        let a = std::f32::consts::TAU * k as f32 / 8.0;
        let (x, y) = (
            (cx + 0.9 * r * a.cos()) as u32,
            (cy + 0.9 * r * a.sin()) as u32,
        );
        let rim = luma(img.pixel(x, y));
        assert!(
            rim < centre - 10.0,
            "rim ({x}, {y}) luma {rim} vs centre {centre}"
        );
    }
}

#[test]
fn flipped_winding_renders_the_same_image() {
    let Some(gpu) = common::gpu() else { return };
    let views = [View::Front, View::Iso, View::Top, View::Bottom];
    for (name, mesh) in [
        ("icosphere", common::icosphere(2)),
        ("hemisphere", hemisphere(2)),
    ] {
        let mut o = opts(96, &views);
        o.wireframe = true;
        let mut flipped = mesh.clone();
        flipped.flip_winding();
        let a = render_image(gpu, &mesh, &o).unwrap();
        let b = render_image(gpu, &flipped, &o).unwrap();
        let diff = max_channel_diff(&a, &b);
        assert!(diff <= 1, "{name}: images differ by {diff}/255");
    }
}

#[test]
fn open_surface_is_lit_from_both_sides() {
    // The hemisphere's inside (seen from below) must be lit, not black.
    let Some(gpu) = common::gpu() else { return };
    let img = render_image(gpu, &hemisphere(2), &opts(96, &[View::Bottom])).unwrap();
    let centre = luma(img.pixel(48, 48));
    assert!(centre > 120.0, "inside of the cap is dark: luma {centre}");
}

#[test]
fn wireframe_adds_dark_line_pixels() {
    let Some(gpu) = common::gpu() else { return };
    let mesh = common::icosphere(1);
    let mut o = opts(128, &[View::Front]);
    let dark = |img: &Image| {
        (CAPTION_BAND..img.height)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .filter(|&(x, y)| luma(img.pixel(x, y)) < 70.0)
            .count()
    };
    let plain = dark(&render_image(gpu, &mesh, &o).unwrap());
    o.wireframe = true;
    let wired = dark(&render_image(gpu, &mesh, &o).unwrap());
    assert_eq!(plain, 0, "shading alone should have no near-black pixels");
    assert!(wired > 300, "only {wired} line pixels");
}

#[test]
fn colour_map_runs_from_purple_to_yellow_with_a_legend() {
    let Some(gpu) = common::gpu() else { return };
    let mesh = with_field(common::icosphere(3), "height", |p| p.y);
    let size = 128;
    let mut o = opts(size, &[View::Front]);
    o.scalars = Some("height".into());
    let img = render_image(gpu, &mesh, &o).unwrap();
    assert!(img.width > size, "no legend strip");
    assert_eq!(img.height, size);
    // Front view: +y (max) near the top of the disc, −y (min) near the bottom.
    let (cx, cy, r) = disc(size);
    let top = img.pixel(cx as u32, (cy - 0.8 * r) as u32);
    let bottom = img.pixel(cx as u32, (cy + 0.8 * r) as u32);
    assert!(
        top[1] > top[2] + 40 && top[0] > 100,
        "max end not yellow: {top:?}"
    );
    assert!(
        bottom[2] > bottom[1] + 20 && bottom[0] > bottom[1],
        "min end not purple: {bottom:?}"
    );
    // The legend strip holds the bar's end colours and dark text.
    let strip: Vec<[u8; 4]> = (0..img.height)
        .flat_map(|y| (size..img.width).map(move |x| (x, y)))
        .map(|(x, y)| img.pixel(x, y))
        .collect();
    let near = |p: &[u8; 4], c: [u8; 3]| (0..3).all(|k| p[k].abs_diff(c[k]) <= 3);
    assert!(
        strip.iter().any(|p| near(p, [253, 231, 37])),
        "no viridis yellow"
    );
    assert!(
        strip.iter().any(|p| near(p, [68, 1, 84])),
        "no viridis purple"
    );
    assert!(strip.iter().any(|p| luma(*p) < 60.0), "no legend text");
}

#[test]
fn user_range_clamps_the_colours() {
    let Some(gpu) = common::gpu() else { return };
    let mesh = with_field(common::icosphere(2), "height", |p| p.y);
    let mut o = opts(96, &[View::Front]);
    o.scalars = Some("height".into());
    o.scalar_range = Some((5.0, 6.0));
    let img = render_image(gpu, &mesh, &o).unwrap();
    // Every value lies below the range: the whole sphere takes the min colour
    // (purple: blue above green), top and bottom alike.
    for y in [30, 48, 70] {
        let p = img.pixel(48, y);
        assert!(p[2] > p[1] + 20, "({y}) {p:?}");
    }
    o.scalar_range = Some((1.0, 1.0));
    assert!(matches!(
        render_image(gpu, &mesh, &o),
        Err(Error::InvalidParameter { ref name, .. }) if name == "render: scalar range"
    ));
}

#[test]
fn views_form_the_expected_grid() {
    let Some(gpu) = common::gpu() else { return };
    let mesh = common::cube();
    let views = [View::Front, View::Back, View::Right, View::Top, View::Iso];
    let mut o = opts(64, &views);
    o.height = 48;
    let img = render_image(gpu, &mesh, &o).unwrap();
    assert_eq!((img.width, img.height), (3 * 64, 2 * 48));
    // Five cells drawn, the sixth (bottom right) left empty.
    for (k, (cx, cy)) in [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1)]
        .into_iter()
        .enumerate()
    {
        assert!(
            !is_background(img.pixel(cx * 64 + 32, cy * 48 + 30)),
            "view {k} is empty"
        );
    }
    assert!((128..192).all(|x| (48..96).all(|y| is_background(img.pixel(x, y)))));
    o.title = Some("cube".into());
    let titled = render_image(gpu, &mesh, &o).unwrap();
    assert_eq!((titled.width, titled.height), (192, 96 + TITLE_HEIGHT));
    assert_eq!(
        titled.rgba[(TITLE_HEIGHT * 192 * 4) as usize..],
        img.rgba[..],
        "the title band shifts the grid down unchanged"
    );
}

#[test]
fn panels_share_one_framing_and_one_colour_range() {
    let Some(gpu) = common::gpu() else { return };
    let big = with_field(common::icosphere(3), "d", |_| 0.0);
    let mut small = with_field(common::icosphere(3), "d", |_| 1.0);
    for p in &mut small.positions {
        *p *= 0.5;
    }
    let size = 128;
    let panels = [
        Panel {
            mesh: &big,
            caption: "before".into(),
            scalars: Some("d".into()),
        },
        Panel {
            mesh: &small,
            caption: "after".into(),
            scalars: Some("d".into()),
        },
    ];
    let o = opts(size, &[View::Front, View::Iso]);
    let img = render_panels(gpu, &panels, &o).unwrap();
    assert!(img.width > 2 * size, "legend strip expected");
    assert_eq!(img.height, 2 * size);
    // Widths of the discs along the centre row of the front views.
    let (cx, cy, _) = disc(size);
    let width = |x0: u32| {
        (x0..x0 + size)
            .filter(|&x| !is_background(img.pixel(x, cy as u32)))
            .count() as f32
    };
    let (wb, ws) = (width(0), width(size));
    assert!(
        (ws / wb - 0.5).abs() < 0.03,
        "widths {wb} and {ws}: not one framing"
    );
    // One range [0, 1]: the constant-0 mesh is purple, the constant-1 yellow.
    let b = img.pixel(cx as u32, cy as u32);
    let s = img.pixel(size + cx as u32, cy as u32);
    assert!(b[2] > b[1], "before {b:?}");
    assert!(s[1] > s[2] + 40, "after {s:?}");
}

#[test]
fn bad_requests_are_errors() {
    let Some(gpu) = common::gpu() else { return };
    let mut mesh = with_field(common::tetra(), "alpha", |p| p.x);
    mesh.scalars.push(ScalarField {
        name: "beta".into(),
        values: vec![0.0; 4],
    });
    let mut o = opts(32, &[View::Front]);
    o.scalars = Some("gamma".into());
    let err = render_image(gpu, &mesh, &o).unwrap_err();
    match err.root() {
        Error::Unknown { kind, name, known } => {
            assert_eq!((*kind, name.as_str()), ("scalar field", "gamma"));
            assert_eq!(known, &["alpha", "beta"]);
        }
        other => panic!("expected an error naming the fields, got {other:?}"),
    }
    let empty = TriMesh::new(vec![Vec3::ZERO; 3], vec![]).unwrap();
    assert!(matches!(
        render_image(gpu, &empty, &opts(32, &[View::Front])),
        Err(Error::Empty { .. })
    ));
    assert!(matches!(
        render_image(gpu, &common::tetra(), &opts(32, &[])),
        Err(Error::Empty { ref what }) if what == "render: views"
    ));
    assert!(matches!(
        render_image(gpu, &common::tetra(), &opts(0, &[View::Front])),
        Err(Error::InvalidParameter { ref name, .. }) if name == "render: view size"
    ));
    let bad = TriMesh {
        positions: vec![Vec3::ZERO; 3],
        triangles: vec![[0, 1, 7]],
        scalars: vec![],
    };
    assert!(matches!(
        render_image(gpu, &bad, &opts(32, &[View::Front])),
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
fn view_names_parse() {
    assert_eq!("side".parse::<View>().unwrap(), View::Right);
    for &v in View::ALL {
        assert_eq!(v.name().parse::<View>().unwrap(), v);
        assert_eq!(v.to_string(), v.name());
    }
    for bad in ["Front", "diagonal"] {
        match bad.parse::<View>() {
            Err(Error::Unknown { kind, name, known }) => {
                assert_eq!((kind, name.as_str()), ("view", bad));
                assert!(known.iter().any(|k| k == "front") && known.iter().any(|k| k == "side"));
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
}

#[test]
fn png_file_round_trips() {
    let Some(gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tetra.png");
    let o = opts(40, &[View::Front, View::Iso]);
    render_png(gpu, &common::tetra(), &o, &path).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (80, 40));
    assert_eq!(info.color_type, png::ColorType::Rgba);
    let direct = render_image(gpu, &common::tetra(), &o).unwrap();
    assert_eq!(&buf[..info.buffer_size()], &direct.rgba[..]);
    // Only the PNG is left in the folder (the write went through a temp file).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// Fraction of a view's pixels (below the caption band) that the mesh covers.
fn coverage(img: &Image, x0: u32, y0: u32, w: u32, h: u32) -> f32 {
    let mut hit = 0;
    for y in y0 + CAPTION_BAND..y0 + h {
        for x in x0..x0 + w {
            hit += usize::from(!is_background(img.pixel(x, y)));
        }
    }
    hit as f32 / (w * (h - CAPTION_BAND)) as f32
}

#[test]
fn real_meshes_render_framed_and_winding_independent() {
    let Some(gpu) = common::gpu() else { return };
    for (rel, min_cover) in [
        ("fran_cut.vtk", 0.15),
        ("bunny.ply", 0.2),
        ("fsu/footbones.ply", 0.08),
    ] {
        let Some(mesh) = common::real_mesh(rel) else {
            return;
        };
        let o = RenderOptions {
            width: 128,
            height: 128,
            views: vec![View::Front, View::Iso],
            ..Default::default()
        };
        let img = render_image(gpu, &mesh, &o).unwrap();
        for x0 in [0, 128] {
            let c = coverage(&img, x0, 0, 128, 128);
            assert!(c > min_cover, "{rel}: view at x={x0} covers only {c}");
            // Framed with a margin: the outermost columns stay empty.
            for y in CAPTION_BAND..128 {
                assert!(
                    is_background(img.pixel(x0, y)) && is_background(img.pixel(x0 + 127, y)),
                    "{rel}: clipped at row {y}"
                );
            }
        }
        let mut flipped = mesh.clone();
        flipped.flip_winding();
        let diff = max_channel_diff(&img, &render_image(gpu, &flipped, &o).unwrap());
        assert!(diff <= 1, "{rel}: flipped winding differs by {diff}/255");
    }
}

#[test]
fn fran_front_view_faces_the_face() {
    // fran_cut is an open face scan looking toward ≈ (+0.81, 0, −0.59); with
    // Facing::Auto the front view sees the face square on, so it covers
    // more of the view than the fixed +z view, which sees it from the side.
    let Some(gpu) = common::gpu() else { return };
    let Some(mesh) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let mut o = RenderOptions {
        width: 128,
        height: 128,
        ..Default::default()
    };
    let auto = coverage(&render_image(gpu, &mesh, &o).unwrap(), 0, 0, 128, 128);
    o.facing = Facing::Axes;
    let axes = coverage(&render_image(gpu, &mesh, &o).unwrap(), 0, 0, 128, 128);
    assert!(auto > axes + 0.05, "auto {auto} vs axes {axes}");
}

/// Regression: a field that is 0 almost everywhere with a few tiny positive
/// values (a relaxed mesh's displacement far from the move) drew grey
/// "no value" hairlines where interpolated zeros rounded below 0.
#[test]
fn near_zero_scalars_draw_no_hairlines() {
    let Some(gpu) = common::gpu() else { return };
    let base = common::icosphere(3);
    let n = base.n_vertices();
    let field = |tiny: f32| {
        let mut m = base.clone();
        let values = (0..n)
            .map(|i| {
                if i == 0 {
                    1.0
                } else if i % 3 == 0 {
                    tiny
                } else {
                    0.0
                }
            })
            .collect();
        m.scalars.push(ScalarField {
            name: "d".into(),
            values,
        });
        m
    };
    let mut o = opts(160, &[View::Front, View::Back]);
    o.scalars = Some("d".into());
    // A fixed range keeps both legends continuous (the exact 0/1 field
    // would get swatches): only the surfaces are compared.
    o.scalar_range = Some((0.0, 1.0));
    let a = render_image(gpu, &field(1e-12), &o).unwrap();
    let b = render_image(gpu, &field(0.0), &o).unwrap();
    let diff = max_channel_diff(&a, &b);
    assert!(diff <= 1, "near-zero values change the image by {diff}/255");
}
