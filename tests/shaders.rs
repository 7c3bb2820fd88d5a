//! Every WGSL file parses and validates with naga (capabilities = what the
//! file's registry entry says it needs, mapped the way wgpu maps them), the
//! registry and the folders list the same files, and the host side agrees
//! with naga's reflection: uniform `Params` layouts (encase vs naga's
//! `Layouter`), binding tables (group, binding, address space, access) and
//! `WG_SIZE` (SPEC §0.3, STYLE "Rust ↔ GPU").

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use chisel::gpu::{Kernel, Shader, preprocess};
use chisel::tissue::gpu as tissue;
use chisel::{hscan, normals, reduce, scan, surface};
use naga::valid::{Capabilities, ValidationFlags, Validator};
use wgpu::BufferBindingType as B;

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

/// What the host binds and dispatches for a kernel.
struct Host {
    /// Binding types at `@group(0) @binding(i)`.
    bindings: &'static [B],
    /// Invocations per workgroup the host divides by.
    wg_size: u32,
    /// Other WGSL `const`s the host relies on, with the host's values.
    consts: &'static [(&'static str, u32)],
    /// The encase `Params` bytes with distinct field values, and each field's
    /// (name, value) in declaration order.
    params: (Vec<u8>, Vec<(&'static str, u32)>),
}

fn encase_bytes<T: encase::ShaderType + encase::internal::WriteInto>(v: &T) -> Vec<u8> {
    let mut buf = encase::UniformBuffer::new(Vec::new());
    buf.write(v).unwrap();
    buf.into_inner()
}

/// `kernels/vertex_normals.wgsl`'s bindings as `normals::gpu` binds them
/// (params, positions, triangles, offsets, tri_ids, normals).
const NORMALS_BINDINGS: &[B] = &[
    B::Uniform,
    B::Storage { read_only: true },
    B::Storage { read_only: true },
    B::Storage { read_only: true },
    B::Storage { read_only: true },
    B::Storage { read_only: false },
];

fn host(kernel: Kernel) -> Host {
    match kernel {
        Kernel::VertexNormals => Host {
            bindings: NORMALS_BINDINGS,
            wg_size: 256,
            consts: &[],
            params: (
                encase_bytes(&normals::gpu::Params { n_vertices: 0xA1 }),
                vec![("n_vertices", 0xA1)],
            ),
        },
        Kernel::BoundsReduce | Kernel::RangeReduce => Host {
            bindings: reduce::gpu::BINDINGS,
            wg_size: reduce::gpu::WG_SIZE,
            consts: &[("BLOCK", reduce::gpu::BLOCK)],
            params: (
                encase_bytes(&reduce::gpu::Params {
                    n_items: 0xB1,
                    pairs: 0xB2,
                }),
                vec![("n_items", 0xB1), ("pairs", 0xB2)],
            ),
        },
        Kernel::ExclusiveScanBlocks | Kernel::ExclusiveScanAdd => Host {
            bindings: if kernel == Kernel::ExclusiveScanBlocks {
                scan::gpu::BLOCKS_BINDINGS
            } else {
                scan::gpu::ADD_BINDINGS
            },
            wg_size: scan::gpu::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&scan::gpu::Params { n: 0xC1 }),
                vec![("n", 0xC1)],
            ),
        },
        Kernel::McClassify => Host {
            bindings: surface::gpu::CLASSIFY_BINDINGS,
            wg_size: surface::gpu::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&surface::gpu::ClassifyParams {
                    nx: 0xD1,
                    ny: 0xD2,
                    nz: 0xD3,
                    z_first: 0xD4,
                    z_begin: 0xD5,
                    n_layers: 0xD6,
                    blocks_per_layer: 0xD7,
                    level: f32::from_bits(0xD8),
                }),
                vec![
                    ("nx", 0xD1),
                    ("ny", 0xD2),
                    ("nz", 0xD3),
                    ("z_first", 0xD4),
                    ("z_begin", 0xD5),
                    ("n_layers", 0xD6),
                    ("blocks_per_layer", 0xD7),
                    ("level", 0xD8),
                ],
            ),
        },
        Kernel::McVertices => Host {
            bindings: surface::gpu::VERTICES_BINDINGS,
            wg_size: surface::gpu::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&surface::gpu::VerticesParams {
                    nx: 0xE1,
                    ny: 0xE2,
                    nz: 0xE3,
                    z_first: 0xE4,
                    z_begin: 0xE5,
                    n_layers: 0xE6,
                    n_owned: 0xE7,
                    blocks_per_layer: 0xE8,
                    v_start: 0xE9,
                    level: f32::from_bits(0xEA),
                }),
                vec![
                    ("nx", 0xE1),
                    ("ny", 0xE2),
                    ("nz", 0xE3),
                    ("z_first", 0xE4),
                    ("z_begin", 0xE5),
                    ("n_layers", 0xE6),
                    ("n_owned", 0xE7),
                    ("blocks_per_layer", 0xE8),
                    ("v_start", 0xE9),
                    ("level", 0xEA),
                ],
            ),
        },
        Kernel::McTriangles => Host {
            bindings: surface::gpu::TRIANGLES_BINDINGS,
            wg_size: surface::gpu::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&surface::gpu::TrianglesParams {
                    nx: 0xF1,
                    ny: 0xF2,
                    nz: 0xF3,
                    z_first: 0xF4,
                    z_begin: 0xF5,
                    n_layers: 0xF6,
                    blocks_per_layer: 0xF7,
                    vb_first: 0xF8,
                    t_start: 0xF9,
                    level: f32::from_bits(0xFA),
                }),
                vec![
                    ("nx", 0xF1),
                    ("ny", 0xF2),
                    ("nz", 0xF3),
                    ("z_first", 0xF4),
                    ("z_begin", 0xF5),
                    ("n_layers", 0xF6),
                    ("blocks_per_layer", 0xF7),
                    ("vb_first", 0xF8),
                    ("t_start", 0xF9),
                    ("level", 0xFA),
                ],
            ),
        },
        Kernel::HullScan | Kernel::HullScanI32x2 | Kernel::HullRows | Kernel::HullRowsI32x2 => {
            Host {
                bindings: if matches!(kernel, Kernel::HullRows | Kernel::HullRowsI32x2) {
                    hscan::gpu::ROWS_BINDINGS
                } else {
                    hscan::gpu::SCAN_BINDINGS
                },
                wg_size: hscan::gpu::WG_SIZE,
                consts: &[],
                params: (
                    encase_bytes(&hscan::gpu::Params {
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
            }
        }
        Kernel::SpringStep => Host {
            bindings: tissue::STEP_BINDINGS,
            wg_size: tissue::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&tissue::SpringStepParams {
                    n_free: 0xD1,
                    use_forces: 0xD2,
                    dt: f32::from_bits(0xD3),
                    damping: f32::from_bits(0xD4),
                    gain: f32::from_bits(0xD5),
                    isotropy: f32::from_bits(0xD6),
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
        },
        Kernel::SpringChebyshev => Host {
            bindings: tissue::STEP_BINDINGS,
            wg_size: tissue::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&tissue::SpringChebyshevParams {
                    n_free: 0xD1,
                    use_forces: 0xD2,
                    h: f32::from_bits(0xD3),
                    momentum: f32::from_bits(0xD4),
                    gain: f32::from_bits(0xD5),
                    isotropy: f32::from_bits(0xD6),
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
        },
        Kernel::TissueReduceMax => Host {
            bindings: tissue::REDUCE_BINDINGS,
            wg_size: tissue::WG_SIZE,
            consts: &[],
            params: (
                encase_bytes(&tissue::ReduceParams {
                    n: 0xE1,
                    mode: 0xE2,
                }),
                vec![("n", 0xE1), ("mode", 0xE2)],
            ),
        },
        #[expect(unreachable_patterns, reason = "fails loudly when a kernel is added")]
        other => panic!(
            "{}: add its host binding table to tests/shaders.rs::host",
            other.path()
        ),
    }
}

fn u32_const(module: &naga::Module, name: &str) -> Option<u32> {
    let c = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?
        .1;
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(v),
        _ => None,
    }
}

/// Bindings, `WG_SIZE` and `Params` layout of every kernel against its host.
#[test]
fn kernels_match_their_host_side() {
    for &kernel in Kernel::ALL {
        let path = kernel.path();
        let module = validate(&path, kernel.source(), kernel.requires());
        let host = host(kernel);

        // Bindings: group 0, numbered 0..n, types as the host binds them.
        let mut reflected: Vec<(u32, u32, B)> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| {
                let rb = g.binding.as_ref()?;
                let ty = match g.space {
                    naga::AddressSpace::Uniform => B::Uniform,
                    naga::AddressSpace::Storage { access } => B::Storage {
                        read_only: !access.contains(naga::StorageAccess::STORE),
                    },
                    other => panic!("{path}: binding in {other:?}"),
                };
                Some((rb.group, rb.binding, ty))
            })
            .collect();
        reflected.sort_by_key(|r| (r.0, r.1));
        let expected: Vec<(u32, u32, B)> = host
            .bindings
            .iter()
            .enumerate()
            .map(|(i, &b)| (0, i as u32, b))
            .collect();
        assert_eq!(reflected, expected, "{path}: bindings vs host table");

        // One compute entry `main`; WG_SIZE = @workgroup_size = host's.
        assert_eq!(module.entry_points.len(), 1, "{path}: entry points");
        let ep = &module.entry_points[0];
        assert_eq!(
            (ep.name.as_str(), ep.stage),
            ("main", naga::ShaderStage::Compute)
        );
        assert_eq!(
            ep.workgroup_size,
            [host.wg_size, 1, 1],
            "{path}: workgroup size"
        );
        assert_eq!(
            u32_const(&module, "WG_SIZE"),
            Some(host.wg_size),
            "{path}: WG_SIZE"
        );

        for (name, value) in host.consts {
            assert_eq!(
                u32_const(&module, name),
                Some(*value),
                "{path}: const {name}"
            );
        }

        // Params: naga's layout vs the bytes encase writes.
        let (bytes, fields) = host.params;
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"))
            .unwrap_or_else(|| panic!("{path}: no `Params` struct"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{path}: `Params` is not a struct");
        };
        assert_eq!(layouter[handle].size, *span);
        assert_eq!(
            bytes.len() as u32,
            *span,
            "{path}: encase size vs naga span"
        );
        let names: Vec<&str> = members.iter().filter_map(|m| m.name.as_deref()).collect();
        let host_names: Vec<&str> = fields.iter().map(|f| f.0).collect();
        assert_eq!(names, host_names, "{path}: Params members");
        for (m, (name, value)) in members.iter().zip(&fields) {
            let at = m.offset as usize;
            let word = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
            assert_eq!(word, *value, "{path}: Params.{name} at offset {at}");
            assert_eq!(layouter[m.ty].size, 4, "{path}: Params.{name} is 4 bytes");
        }
    }
}
