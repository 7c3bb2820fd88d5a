//! Every WGSL file parses and validates with naga (capabilities = what the
//! file's registry entry says it needs, mapped the way wgpu maps them), the
//! registry and the folders list the same files, and the host agrees with
//! the WGSL: every kernel's spec (bindings, workgroup size, constants) is
//! reflected from the WGSL itself and used at run time by the pass builder,
//! which refuses a binding of the wrong kind; here the specs are checked for
//! the house order, the host's uniform `Params` layouts against naga's
//! `Layouter`, and the mirrors' constants against the kernels' (SPEC §0.3,
//! STYLE "Rust ↔ GPU").

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use chisel::gpu::{BindKind, Gpu, GpuArray, UniformBuffer};
use chisel::gpu::{Kernel, Shader, preprocess};
use chisel::tissue::gpu as tissue;
use chisel::{Error, dms, exclusive_scan, hull_scan, implicit, mc, reduce, vertex_normals};
use naga::valid::{Capabilities, ValidationFlags, Validator};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Stems of the `*.wgsl` files directly in `dir`.
fn wgsl_stems(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "wgsl"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// Naga capabilities wgpu grants a device with `features` (full downlevel).
fn capabilities(features: wgpu::Features) -> Capabilities {
    wgpu_naga_bridge::features_to_naga_capabilities(features, wgpu::DownlevelFlags::all())
}

/// Expands imports, parses and validates; panics with naga's report.
fn validate(path: &str, source: &str, features: wgpu::Features) -> naga::Module {
    let source = preprocess(source).unwrap_or_else(|e| panic!("{path}: {e}"));
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("{path}:\n{}", e.emit_to_string(&source)));
    Validator::new(ValidationFlags::all(), capabilities(features))
        .validate(&module)
        .unwrap_or_else(|e| panic!("{path}:\n{}", e.emit_to_string(&source)));
    module
}

/// A registry's entries: (file name, source, required features).
type Entries<'a> = Vec<(String, &'a str, wgpu::Features)>;

/// Both folders hold exactly the registered files, and every one validates.
#[test]
fn every_wgsl_file_is_registered_and_validates() {
    let mut validated = 0;
    let mut found = 0;
    let registries: [(&str, Entries<'_>); 2] = [
        (
            "kernels",
            Kernel::ALL
                .iter()
                .map(|k| (k.name().to_string(), k.source(), k.requires()))
                .collect(),
        ),
        (
            "shaders",
            Shader::ALL
                .iter()
                .map(|s| (s.name().to_string(), s.source(), s.requires()))
                .collect(),
        ),
    ];
    for (dir, entries) in registries {
        let on_disk = wgsl_stems(&root().join(dir));
        let registered: BTreeSet<String> = entries.iter().map(|e| e.0.clone()).collect();
        assert_eq!(
            on_disk.difference(&registered).collect::<Vec<_>>(),
            Vec::<&String>::new(),
            "{dir}/: files missing from the registry"
        );
        assert_eq!(
            registered.difference(&on_disk).collect::<Vec<_>>(),
            Vec::<&String>::new(),
            "{dir}/: registry entries without a file"
        );
        found += on_disk.len();
        for (name, source, features) in entries {
            let path = format!("{dir}/{name}.wgsl");
            let disk = std::fs::read_to_string(root().join(&path)).unwrap();
            assert_eq!(source, disk, "{path}: embedded copy is stale");
            validate(&path, source, features);
            validated += 1;
        }
    }
    assert!(found >= Kernel::ALL.len() + Shader::ALL.len());
    assert_eq!(validated, found, "validated vs .wgsl files found");
}

/// Shared fragments are importable and valid on their own.
#[test]
fn shared_fragments_import_and_validate() {
    let shared = wgsl_stems(&root().join("kernels/shared"));
    assert!(!shared.is_empty());
    for name in shared {
        let source = format!("#import {name}\n");
        validate(
            &format!("kernels/shared/{name}.wgsl"),
            &source,
            wgpu::Features::empty(),
        );
    }
}

/// Kernels validate without any optional capability unless they declare one.
#[test]
fn portable_kernels_need_no_capabilities() {
    for k in Kernel::ALL.iter().filter(|k| k.requires().is_empty()) {
        let source = preprocess(k.source()).unwrap();
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        Validator::new(ValidationFlags::all(), Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {}", k.path(), e.emit_to_string(&source)));
    }
}

/// The encase bytes of a kernel's `Params` with distinct field values, and
/// each field's (name, value) in declaration order.
type Sample = (Vec<u8>, Vec<(&'static str, u32)>);

fn encase_bytes<T: encase::ShaderType + encase::internal::WriteInto>(v: &T) -> Vec<u8> {
    let mut buf = encase::UniformBuffer::new(Vec::new());
    buf.write(v).unwrap();
    buf.into_inner()
}

/// The host's `Params` of `kernel`, written with distinct values.
fn params_sample(kernel: Kernel) -> Sample {
    match kernel {
        Kernel::VertexNormals => (
            encase_bytes(&vertex_normals::gpu::Params { n_vertices: 0xA1 }),
            vec![("n_vertices", 0xA1)],
        ),
        Kernel::BoundsReduce | Kernel::RangeReduce => (
            encase_bytes(&reduce::gpu::Params {
                n_items: 0xB1,
                pairs: 0xB2,
            }),
            vec![("n_items", 0xB1), ("pairs", 0xB2)],
        ),
        Kernel::ExclusiveScanBlocks | Kernel::ExclusiveScanAdd => (
            encase_bytes(&exclusive_scan::gpu::Params { n: 0xC1 }),
            vec![("n", 0xC1)],
        ),
        Kernel::McInside => {
            let (grid, mut fields) = sample_grid_sample(0xC0);
            let p = mc::gpu::InsideParams {
                grid,
                z_begin: 0xC5,
                n_layers: 0xC6,
                row_words: 0xC7,
            };
            fields.extend([("z_begin", 0xC5), ("n_layers", 0xC6), ("row_words", 0xC7)]);
            (encase_bytes(&p), fields)
        }
        Kernel::McClassify => {
            let (rows, mut fields) = bit_rows_sample(0xD0);
            let p = mc::gpu::ClassifyParams {
                rows,
                z_begin: 0xD5,
                n_layers: 0xD6,
                blocks_per_layer: 0xD7,
            };
            fields.extend([
                ("z_begin", 0xD5),
                ("n_layers", 0xD6),
                ("blocks_per_layer", 0xD7),
            ]);
            (encase_bytes(&p), fields)
        }
        Kernel::McVertices => {
            let (grid, mut fields) = sample_grid_sample(0xE0);
            let (rows, row_fields) = bit_rows_sample(0xEA);
            fields.extend(row_fields);
            let p = mc::gpu::VerticesParams {
                grid,
                rows,
                z_begin: 0xE5,
                n_layers: 0xE6,
                n_owned: 0xE7,
                blocks_per_layer: 0xE8,
                v_start: 0xE9,
            };
            fields.extend([
                ("z_begin", 0xE5),
                ("n_layers", 0xE6),
                ("n_owned", 0xE7),
                ("blocks_per_layer", 0xE8),
                ("v_start", 0xE9),
            ]);
            (encase_bytes(&p), fields)
        }
        Kernel::McTriangles => {
            let (rows, mut fields) = bit_rows_sample(0xF0);
            let p = mc::gpu::TrianglesParams {
                rows,
                z_begin: 0xF5,
                n_layers: 0xF6,
                blocks_per_layer: 0xF7,
                vb_first: 0xF8,
                t_start: 0xF9,
            };
            fields.extend([
                ("z_begin", 0xF5),
                ("n_layers", 0xF6),
                ("blocks_per_layer", 0xF7),
                ("vb_first", 0xF8),
                ("t_start", 0xF9),
            ]);
            (encase_bytes(&p), fields)
        }
        Kernel::HullScan | Kernel::HullScanI32x2 | Kernel::HullRows | Kernel::HullRowsI32x2 => (
            encase_bytes(&hull_scan::gpu::Params {
                n_faces: 0xD1,
                n_items: 0xD2,
                nx: 0xD3,
                ny: 0xD4,
                z0: 0xD5,
                origin_x: 0xD6,
                origin_y: 0xD7,
                origin_z: 0xD8,
            }),
            vec![
                ("n_faces", 0xD1),
                ("n_items", 0xD2),
                ("nx", 0xD3),
                ("ny", 0xD4),
                ("z0", 0xD5),
                ("origin_x", 0xD6),
                ("origin_y", 0xD7),
                ("origin_z", 0xD8),
            ],
        ),
        Kernel::SpringStep | Kernel::SpringChebyshev | Kernel::TissueReduceMax => {
            tissue_params_sample(kernel)
        }
        Kernel::DmsBasis => (
            encase_bytes(&dms::basis::gpu::Params { n_points: 0xB1 }),
            vec![("n_points", 0xB1)],
        ),
        Kernel::DmsSurface => (
            encase_bytes(&dms::surface::gpu::Params { n_points: 0xB2 }),
            vec![("n_points", 0xB2)],
        ),
        Kernel::ImplicitField => (
            encase_bytes(&implicit::field::gpu::Params { n_points: 0xC1 }),
            vec![("n_points", 0xC1)],
        ),
        Kernel::ParticleUpdate => particle_params_sample(),
        Kernel::BlobbyEnergy => {
            let f = |v: u32| f32::from_bits(v);
            let p = chisel::blobby::energy::EnergyParams {
                n_points: 0xF1,
                n_prims: 0xF2,
                iso: f(0x3F20_0001),
                inv_m: f(0x3F20_0002),
                alpha: f(0x3F20_0003),
                g_min2: f(0x3F20_0004),
            };
            let fields = vec![
                ("n_points", 0xF1),
                ("n_prims", 0xF2),
                ("iso", 0x3F20_0001),
                ("inv_m", 0x3F20_0002),
                ("alpha", 0x3F20_0003),
                ("g_min2", 0x3F20_0004),
            ];
            (encase_bytes(&p), fields)
        }
        Kernel::NetworkUpdate => {
            let f = |v: u32| f32::from_bits(v);
            let p = chisel::particles::network::NetworkParams {
                n_vertices: 0xE1,
                dt: f(0x3F10_0001),
                delta: f(0x3F10_0002),
                kappa: f(0x3F10_0003),
                rho: f(0x3F10_0004),
                g_min2: f(0x3F10_0005),
                step_max: f(0x3F10_0006),
            };
            let fields = vec![
                ("n_vertices", 0xE1),
                ("dt", 0x3F10_0001),
                ("delta", 0x3F10_0002),
                ("kappa", 0x3F10_0003),
                ("rho", 0x3F10_0004),
                ("g_min2", 0x3F10_0005),
                ("step_max", 0x3F10_0006),
            ];
            (encase_bytes(&p), fields)
        }
        Kernel::RayCast | Kernel::RayHits => {
            let f = |v: u32| f32::from_bits(v);
            let p = chisel::ray_cast::gpu::Params {
                n_rays: 0xD1,
                n_nodes: 0xD2,
                origin_x: f(0x3F30_0001),
                origin_y: f(0x3F30_0002),
                origin_z: f(0x3F30_0003),
            };
            let fields = vec![
                ("n_rays", 0xD1),
                ("n_nodes", 0xD2),
                ("origin_x", 0x3F30_0001),
                ("origin_y", 0x3F30_0002),
                ("origin_z", 0x3F30_0003),
            ];
            (encase_bytes(&p), fields)
        }
        #[expect(unreachable_patterns, reason = "fails loudly when a kernel is added")]
        other => panic!(
            "{}: add its `Params` sample to tests/shaders.rs::params_sample",
            other.path()
        ),
    }
}

/// The marching-cubes kernels' `rows` member (`BitRows`) with distinct
/// values from `base << 8`, and its flattened fields (`rows.<name>`).
fn bit_rows_sample(base: u32) -> (mc::grid::BitRows, Vec<(&'static str, u32)>) {
    let v = |k: u32| (base << 8) + k;
    let rows = mc::grid::BitRows {
        nx: v(1),
        ny: v(2),
        nz: v(3),
        z_first: v(4),
        row_words: v(5),
        unused0: v(6),
        unused1: v(7),
        unused2: v(8),
    };
    let names = [
        "rows.nx",
        "rows.ny",
        "rows.nz",
        "rows.z_first",
        "rows.row_words",
        "rows.unused0",
        "rows.unused1",
        "rows.unused2",
    ];
    (rows, names.into_iter().zip((1..).map(v)).collect())
}

/// The marching-cubes kernels' `grid` member with distinct values from
/// `base << 8`, and its flattened fields (`grid.<name>`).
fn sample_grid_sample(base: u32) -> (mc::grid::SampleGrid, Vec<(&'static str, u32)>) {
    let v = |k: u32| (base << 8) + k;
    let f = |k: u32| f32::from_bits(v(k));
    let grid = mc::grid::SampleGrid {
        nx: v(1),
        ny: v(2),
        nz: v(3),
        z_first: v(4),
        pad: v(5),
        kind: v(6),
        labels: v(7),
        label: f(8),
        outside: f(9),
        level: f(10),
        unused0: v(11),
        unused1: v(12),
    };
    let names = [
        "grid.nx",
        "grid.ny",
        "grid.nz",
        "grid.z_first",
        "grid.pad",
        "grid.kind",
        "grid.labels",
        "grid.label",
        "grid.outside",
        "grid.level",
        "grid.unused0",
        "grid.unused1",
    ];
    (
        grid,
        names.into_iter().zip(1..).map(|(n, k)| (n, v(k))).collect(),
    )
}

/// `particle_update`'s `Params` with distinct values (floats by their bits).
fn particle_params_sample() -> Sample {
    use chisel::particles::wh::UpdateParams;
    let f = |v: u32| f32::from_bits(v);
    let p = UpdateParams {
        nx: 0xD1,
        ny: 0xD2,
        nz: 0xD3,
        n_particles: 0xD4,
        n_cells: 0xD5,
        dt: f(0x3F00_0001),
        delta: f(0x3F00_0002),
        kappa: f(0x3F00_0003),
        alpha: f(0x3F00_0004),
        e_hat: f(0x3F00_0005),
        rho_sigma: f(0x3F00_0006),
        beta_sigma: f(0x3F00_0007),
        sigma_lo: f(0x3F00_0008),
        sigma_hi: f(0x3F00_0009),
        g_min2: f(0x3F00_000A),
        adapt: 0xD6,
    };
    let names = [
        "dt",
        "delta",
        "kappa",
        "alpha",
        "e_hat",
        "rho_sigma",
        "beta_sigma",
        "sigma_lo",
        "sigma_hi",
        "g_min2",
    ];
    let mut fields = vec![
        ("nx", 0xD1),
        ("ny", 0xD2),
        ("nz", 0xD3),
        ("n_particles", 0xD4),
        ("n_cells", 0xD5),
    ];
    fields.extend(
        names
            .iter()
            .enumerate()
            .map(|(k, n)| (*n, 0x3F00_0001 + k as u32)),
    );
    fields.push(("adapt", 0xD6));
    (encase_bytes(&p), fields)
}

/// Every kernel's spec reflects from its WGSL: one compute entry `main`,
/// `@workgroup_size(WG_SIZE)`, the uniform `Params` at binding 0 (and any
/// other uniforms after it), then the buffers it reads, then those it
/// writes (the house order the pass builder's calls follow).
#[test]
fn every_kernel_spec_follows_the_house_order() {
    for &kernel in Kernel::ALL {
        let spec = kernel.spec().unwrap_or_else(|e| panic!("{e}"));
        let path = kernel.path();
        assert_eq!(spec.kernel, kernel);
        assert_eq!(
            spec.const_u32("WG_SIZE").ok(),
            Some(spec.wg_size),
            "{path}: WG_SIZE vs @workgroup_size"
        );
        let rank = |k: &BindKind| match k {
            BindKind::Uniform => 0,
            BindKind::Read => 1,
            BindKind::ReadWrite => 2,
        };
        assert_eq!(spec.bindings.first(), Some(&BindKind::Uniform), "{path}");
        assert!(
            spec.bindings.windows(2).all(|w| rank(&w[0]) <= rank(&w[1])),
            "{path}: bindings {:?} not uniform → read → read-write",
            spec.bindings
        );
    }
}

/// The mirrors' block sizes are the kernels' constants.
#[test]
fn mirrors_use_their_kernels_constants() {
    let spec = |k: Kernel| k.spec().unwrap();
    for k in [Kernel::BoundsReduce, Kernel::RangeReduce] {
        assert_eq!(
            spec(k).const_u32("BLOCK").unwrap() as usize,
            reduce::cpu::BLOCK
        );
    }
    for k in [Kernel::ExclusiveScanBlocks, Kernel::ExclusiveScanAdd] {
        assert_eq!(spec(k).wg_size as usize, exclusive_scan::cpu::WG_SIZE);
    }
    for k in [
        Kernel::McInside,
        Kernel::McClassify,
        Kernel::McVertices,
        Kernel::McTriangles,
    ] {
        assert_eq!(spec(k).wg_size, mc::mirror::WG_SIZE);
    }
    let blobby = spec(Kernel::BlobbyEnergy);
    assert_eq!(blobby.wg_size as usize, chisel::blobby::energy::WG_SIZE);
    assert_eq!(
        blobby.const_u32("POINTS_PER_INVOCATION").unwrap() as usize,
        chisel::blobby::energy::POINTS_PER_INVOCATION
    );
}

/// `Params` layout of every kernel: naga's offsets against the bytes encase
/// writes for the host's struct.
#[test]
fn params_match_the_wgsl_layout() {
    for &kernel in Kernel::ALL {
        let path = kernel.path();
        let module = validate(&path, kernel.source(), kernel.requires());
        let (bytes, fields) = params_sample(kernel);
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"))
            .unwrap_or_else(|| panic!("{path}: no `Params` struct"));
        let naga::TypeInner::Struct { span, .. } = &ty.inner else {
            panic!("{path}: `Params` is not a struct");
        };
        assert_eq!(layouter[handle].size, *span);
        assert_eq!(
            bytes.len() as u32,
            *span,
            "{path}: encase size vs naga span"
        );
        let members = flat_members(&module, handle, "", 0);
        let names: Vec<&str> = members.iter().map(|m| m.0.as_str()).collect();
        let host_names: Vec<&str> = fields.iter().map(|f| f.0).collect();
        assert_eq!(names, host_names, "{path}: Params members");
        for ((_, offset, ty), (name, value)) in members.iter().zip(&fields) {
            let at = *offset as usize;
            let word = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
            assert_eq!(word, *value, "{path}: Params.{name} at offset {at}");
            assert_eq!(layouter[*ty].size, 4, "{path}: Params.{name} is 4 bytes");
        }
    }
}

/// The members of struct `handle` with their offsets from `base`, members
/// of nested structs flattened as `outer.inner`.
fn flat_members(
    module: &naga::Module,
    handle: naga::Handle<naga::Type>,
    prefix: &str,
    base: u32,
) -> Vec<(String, u32, naga::Handle<naga::Type>)> {
    let naga::TypeInner::Struct { members, .. } = &module.types[handle].inner else {
        unreachable!("only structs are flattened")
    };
    let mut out = Vec::new();
    for m in members {
        let name = format!("{prefix}{}", m.name.as_deref().unwrap_or("?"));
        if matches!(module.types[m.ty].inner, naga::TypeInner::Struct { .. }) {
            out.extend(flat_members(
                module,
                m.ty,
                &format!("{name}."),
                base + m.offset,
            ));
        } else {
            out.push((name, base + m.offset, m.ty));
        }
    }
    out
}

/// The host's `FieldParams` (the second uniform of every kernel that
/// imports `skeletal_field`) has the WGSL struct's members at its offsets.
#[test]
fn field_params_match_the_wgsl_layout() {
    use glam::{UVec3, Vec3};
    let host = implicit::field::FieldParams {
        grid_origin: Vec3::new(1.0, 2.0, 3.0),
        inv_cell: 4.0,
        grid_dims: UVec3::new(5, 6, 7),
        n_prims: 8,
        iso: 9.0,
        blend_max: 10,
        piece_base: 11,
        cell_base: 12,
    };
    let bytes = encase_bytes(&host);
    let words: Vec<u32> = [1.0f32, 2.0, 3.0, 4.0]
        .iter()
        .map(|f| f.to_bits())
        .chain([5, 6, 7, 8, 9.0f32.to_bits(), 10, 11, 12])
        .collect();
    let mut users = 0;
    for &kernel in Kernel::ALL {
        let path = kernel.path();
        let module = validate(&path, kernel.source(), kernel.requires());
        let Some((handle, ty)) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("FieldParams"))
        else {
            continue;
        };
        users += 1;
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{path}: `FieldParams` is not a struct");
        };
        assert_eq!(layouter[handle].size, *span);
        assert_eq!(
            bytes.len() as u32,
            *span,
            "{path}: encase size vs naga span"
        );
        // Every 4-byte word of the host bytes at the WGSL members' offsets.
        let mut k = 0;
        for m in members {
            let n = layouter[m.ty].size as usize / 4;
            for w in 0..n {
                let at = m.offset as usize + 4 * w;
                let word = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
                assert_eq!(word, words[k], "{path}: FieldParams.{:?} word {w}", m.name);
                k += 1;
            }
        }
        assert_eq!(k, words.len(), "{path}: FieldParams members");
    }
    assert!(users >= 1, "no kernel imports skeletal_field");
}

/// The pass builder refuses bindings that disagree with the WGSL: a read
/// where the kernel writes, one binding too few, one too many. Binding the
/// declared kinds in order succeeds (the control).
#[test]
fn pass_builder_refuses_bindings_the_wgsl_does_not_declare() {
    let Some(gpu) = chisel::gpu::gpu_for_tests().unwrap_or_else(|e| panic!("{e}")) else {
        return;
    };
    let gpu: &Gpu = &gpu;
    let params =
        UniformBuffer::new(gpu, "test.params", &exclusive_scan::gpu::Params { n: 4 }).unwrap();
    let a = GpuArray::<u32>::from_slice(gpu, "test.a", &[1, 2, 3, 4]).unwrap();
    let b = GpuArray::<u32>::zeroed(gpu, "test.b", 4).unwrap();
    // exclusive_scan_add: params, read offsets, read-write scanned.
    let binder = || {
        gpu.kernel(Kernel::ExclusiveScanAdd)
            .unwrap()
            .uniform(&params)
    };
    assert!(binder().read(&a).write(&b).bind().is_ok());
    let refused = |r: chisel::Result<chisel::gpu::BoundKernel>, what: &str| match r {
        Err(Error::Kernel { name, message }) => {
            assert_eq!(name, "exclusive_scan_add");
            assert!(message.contains(what), "{message}");
        }
        other => panic!("expected a refusal naming {what}: {other:?}"),
    };
    refused(binder().read(&a).read(&b).bind(), "binding 2 is ReadWrite");
    refused(binder().read(&a).bind(), "2 of its 3 bindings");
    refused(
        binder().read(&a).write(&b).write(&b).bind(),
        "declares 3 bindings",
    );
}

/// The tissue kernels' `Params` samples (one struct per kernel).
fn tissue_params_sample(kernel: Kernel) -> Sample {
    let f = f32::from_bits;
    match kernel {
        Kernel::SpringStep => (
            encase_bytes(&tissue::SpringStepParams {
                n_free: 0xD1,
                use_forces: 0xD2,
                dt: f(0xD3),
                damping: f(0xD4),
                gain: f(0xD5),
                isotropy: f(0xD6),
            }),
            vec![
                ("n_free", 0xD1),
                ("use_forces", 0xD2),
                ("dt", 0xD3),
                ("damping", 0xD4),
                ("gain", 0xD5),
                ("isotropy", 0xD6),
            ],
        ),
        Kernel::SpringChebyshev => (
            encase_bytes(&tissue::SpringChebyshevParams {
                n_free: 0xD1,
                use_forces: 0xD2,
                h: f(0xD3),
                momentum: f(0xD4),
                gain: f(0xD5),
                isotropy: f(0xD6),
            }),
            vec![
                ("n_free", 0xD1),
                ("use_forces", 0xD2),
                ("h", 0xD3),
                ("momentum", 0xD4),
                ("gain", 0xD5),
                ("isotropy", 0xD6),
            ],
        ),
        _ => (
            encase_bytes(&tissue::ReduceParams {
                n: 0xE1,
                mode: 0xE2,
            }),
            vec![("n", 0xE1), ("mode", 0xE2)],
        ),
    }
}
