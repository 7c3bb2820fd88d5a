//! The inputs of the four marching-cubes kernels, made by their mirrors in
//! sequence (`mc::mirror`), for the per-kernel parity modules `mc_inside`,
//! `mc_classify`, `mc_vertices` and `mc_triangles`: each GPU kernel runs on
//! exactly the inputs its mirror gets, so a divergence names its kernel.
//! A stage set covers the whole grid, or one emission slab `[a, b)` of
//! point layers with the offsets and sample window the production path
//! gives it (`mc::gpu`).

use chisel::mc::gpu::{ClassifyParams, InsideParams, TrianglesParams, VerticesParams};
use chisel::mc::grid::{BitRows, inner_layers, sample_grid, sample_words};
use chisel::mc::mirror::{self, WG_SIZE};
use chisel::mc::{Field, IsoSpec, tables};
use chisel::parity::Mismatch;
use chisel::volume::{Volume, VolumeData};

use crate::common;

/// One fixture's inputs and mirror outputs, kernel by kernel.
pub struct Stages {
    pub what: String,
    pub table: Vec<u32>,
    /// `mc_inside` of the classification (whole grid) and of the emission
    /// slab, with their samples and flags.
    pub classify_inside: InsideParams,
    pub classify_samples: Vec<u32>,
    pub classify_bits: Vec<u32>,
    pub emit_inside: InsideParams,
    pub emit_samples: Vec<u32>,
    pub emit_bits: Vec<u32>,
    pub classify: ClassifyParams,
    pub block_counts: Vec<[u32; 2]>,
    pub vertices: VerticesParams,
    pub vertex_offsets: Vec<u32>,
    pub vert_base: Vec<u32>,
    pub positions: Vec<[f32; 4]>,
    pub triangles_params: TrianglesParams,
    pub triangle_offsets: Vec<u32>,
    pub triangles: Vec<[u32; 4]>,
}

/// Exclusive scan with the total appended (the host scan between passes).
fn scan(values: impl Iterator<Item = u32>) -> Vec<u32> {
    let mut sum = 0;
    let mut out: Vec<u32> = values
        .map(|v| {
            sum += v;
            sum - v
        })
        .collect();
    out.push(sum);
    out
}

/// The inside flags of padded layers `z0..z1` from `samples` (words of
/// `grid`), by the mirror.
fn inside(
    field: &Field<'_>,
    grid: chisel::mc::grid::SampleGrid,
    samples: &[u32],
    z0: usize,
    z1: usize,
) -> (InsideParams, BitRows, Vec<u32>) {
    let rows = BitRows::new(field, z0);
    let params = InsideParams {
        grid,
        z_begin: z0 as u32,
        n_layers: (z1 - z0) as u32,
        row_words: rows.row_words,
    };
    let mut bits = vec![u32::MAX; rows.words(z1 - z0)];
    mirror::mc_inside(&params, samples, &mut bits);
    (params, rows, bits)
}

/// The stages of `vol` at `iso` (border closed or open) for point layers
/// `[a, b)` of the emission (`None`: the whole grid); classification always
/// covers the whole grid. Samples are the words the production path
/// uploads (`mc::grid`): the whole volume, and the slab's window of inner
/// layers; the inside flags are those of the classification (whole grid)
/// and of the emission slab's layers and the two above.
pub fn stages(
    what: &str,
    vol: &Volume,
    iso: IsoSpec,
    close: bool,
    slab: Option<(usize, usize)>,
) -> Stages {
    let field = Field::new(vol, iso, close).unwrap();
    let [nx, ny, nz] = field.dims;
    let layer = nx * ny;
    let samples = sample_words(&field, 0, vol.dims[2]).unwrap();
    let table = tables::table().flat();
    let bpl = layer.div_ceil(WG_SIZE as usize);
    let nz32 = nz as u32;
    let (classify_inside, rows, classify_bits) =
        inside(&field, sample_grid(&field, 0), &samples, 0, nz);
    let classify = ClassifyParams {
        rows,
        z_begin: 0,
        n_layers: nz32,
        blocks_per_layer: bpl as u32,
    };
    let mut block_counts = vec![[0u32; 2]; nz * bpl];
    mirror::mc_classify(&classify, &classify_bits, &table, &mut block_counts);
    let off_v = scan(block_counts.iter().map(|c| c[0]));
    let off_t = scan(block_counts.iter().map(|c| c[1]));
    let (a, b) = slab.unwrap_or((0, nz));
    let vb_layers = (b + 1).min(nz) - a;
    let cell_layers = b.min(nz - 1).saturating_sub(a);
    let (k0, k1) = inner_layers(&field, a, (b + 2).min(nz));
    let emit_samples = sample_words(&field, k0, k1).unwrap();
    let grid = sample_grid(&field, k0);
    let (emit_inside, rows, emit_bits) = inside(&field, grid, &emit_samples, a, (b + 2).min(nz));
    let vertices = VerticesParams {
        grid,
        rows,
        z_begin: a as u32,
        n_layers: vb_layers as u32,
        n_owned: (b - a) as u32,
        blocks_per_layer: bpl as u32,
        v_start: off_v[a * bpl],
    };
    let vertex_offsets = off_v[a * bpl..=(a + vb_layers) * bpl].to_vec();
    let mut vert_base = vec![0u32; vb_layers * layer];
    let mut positions = vec![[f32::NAN; 4]; (off_v[b * bpl] - off_v[a * bpl]) as usize];
    mirror::mc_vertices(
        &vertices,
        &emit_samples,
        &emit_bits,
        &vertex_offsets,
        &mut vert_base,
        &mut positions,
    );
    let triangles_params = TrianglesParams {
        rows,
        z_begin: a as u32,
        n_layers: cell_layers as u32,
        blocks_per_layer: bpl as u32,
        vb_first: a as u32,
        t_start: off_t[a * bpl],
    };
    let triangle_offsets = off_t[a * bpl..=(a + cell_layers.max(1)) * bpl].to_vec();
    let n_t = off_t[(a + cell_layers) * bpl] - off_t[a * bpl];
    let mut triangles = vec![[u32::MAX; 4]; n_t as usize];
    mirror::mc_triangles(
        &triangles_params,
        &emit_bits,
        &table,
        &triangle_offsets,
        &vert_base,
        &mut triangles,
    );
    assert!(
        !triangles.is_empty(),
        "{what}: an empty surface proves nothing"
    );
    Stages {
        what: what.into(),
        table,
        classify_inside,
        classify_samples: samples,
        classify_bits,
        emit_inside,
        emit_samples,
        emit_bits,
        classify,
        block_counts,
        vertices,
        vertex_offsets,
        vert_base,
        positions,
        triangles_params,
        triangle_offsets,
        triangles,
    }
}

/// A random i16 volume (samples on the level exercise the clamp).
pub fn random_volume(seed: u64, dims: [usize; 3]) -> Volume {
    let mut next = common::xorshift(seed);
    let data: Vec<i16> = (0..dims.iter().product::<usize>())
        .map(|_| (next() % 2000) as i16)
        .collect();
    Volume::new(
        dims,
        [0.7, 1.1, 1.3],
        [-3.0, 2.0, 5.0],
        VolumeData::I16(data),
    )
    .unwrap()
}

/// `vol`'s samples as another type (`f`: the i16 value to the new one).
fn retyped(vol: &Volume, f: impl Fn(&[i16]) -> VolumeData) -> Volume {
    let VolumeData::I16(v) = &vol.data else {
        unreachable!("random volumes are i16")
    };
    Volume::new(vol.dims, vol.spacing, vol.origin, f(v)).unwrap()
}

/// The fixtures every kernel module runs: random volumes (levels between
/// and on the samples) in i16, and as u16, i8, f32 (each uploaded in its
/// own type) and f64 (converted to f32 on the host), with the border
/// closed and open; rows of 64 and 66 points (whole and partial flag
/// words); label volumes (u8 in its own type, i32 converted); an
/// emission slab in the middle of the grid (closed and open); and the real
/// CT (headsq at the skin and bone levels).
pub fn fixtures() -> Vec<Stages> {
    let mut out = Vec::new();
    for seed in 1..=3u64 {
        let vol = random_volume(seed, [23, 17, 11]);
        for level in [1000.5, 1000.0] {
            let what = format!("random {seed} level {level}");
            out.push(stages(&what, &vol, IsoSpec::Level(level), true, None));
        }
    }
    let vol = random_volume(4, [23, 17, 11]);
    let as_u16 = retyped(&vol, |v| {
        VolumeData::U16(v.iter().map(|&x| x as u16).collect())
    });
    let as_i8 = retyped(&vol, |v| {
        VolumeData::I8(v.iter().map(|&x| (x % 256 - 128) as i8).collect())
    });
    let as_f32 = retyped(&vol, |v| {
        VolumeData::F32(v.iter().map(|&x| f32::from(x) * 0.5).collect())
    });
    let as_f64 = retyped(&vol, |v| {
        VolumeData::F64(v.iter().map(|&x| f64::from(x) / 3.0).collect())
    });
    for close in [true, false] {
        let kinds = [
            ("u16", &as_u16, 1000.5),
            ("i8", &as_i8, 0.5),
            ("f32", &as_f32, 500.0),
            ("f64", &as_f64, 333.3),
        ];
        for (name, vol, level) in kinds {
            let what = format!("random {name} level {level} closed {close}");
            out.push(stages(&what, vol, IsoSpec::Level(level), close, None));
        }
    }
    let mut next = common::xorshift(9);
    let data: Vec<u8> = (0..30 * 20 * 10).map(|_| (next() % 4) as u8).collect();
    let wide = VolumeData::I32(data.iter().map(|&x| i32::from(x) - 1).collect());
    let labels = Volume::new([30, 20, 10], [1.0; 3], [0.0; 3], VolumeData::U8(data)).unwrap();
    out.push(stages("labels", &labels, IsoSpec::Label(2.0), true, None));
    let labels = Volume::new([30, 20, 10], [1.0; 3], [0.0; 3], wide).unwrap();
    out.push(stages(
        "labels i32",
        &labels,
        IsoSpec::Label(1.0),
        false,
        None,
    ));
    // Rows of whole flag words (64 points open: two words) and of a
    // partial last word (66 closed: three words, two bits in the last).
    let vol = random_volume(6, [64, 9, 7]);
    for close in [true, false] {
        let what = format!("64 wide closed {close}");
        out.push(stages(&what, &vol, IsoSpec::Level(1000.5), close, None));
    }
    let vol = random_volume(5, [40, 30, 24]);
    for close in [true, false] {
        out.push(stages(
            &format!("slab 7..15 closed {close}"),
            &vol,
            IsoSpec::Level(1000.5),
            close,
            Some((7, 15)),
        ));
    }
    if let Some(vol) = common::real_volume("headsq/quarter.nhdr") {
        for level in [500.0, 1150.0] {
            out.push(stages(
                &format!("headsq {level}"),
                &vol,
                IsoSpec::Level(level),
                true,
                None,
            ));
        }
    }
    out
}

/// Positions within `ulps` units in the last place per coordinate (0: bit
/// for bit); the `w` lanes (edge ids) exactly.
pub fn compare_positions(
    what: &str,
    cpu: &[[f32; 4]],
    gpu: &[[f32; 4]],
    ulps: u32,
) -> Result<(), Mismatch> {
    let close = |a: &[f32; 4], b: &[f32; 4]| {
        a[3].to_bits() == b[3].to_bits()
            && (0..3).all(|k| a[k].to_bits().abs_diff(b[k].to_bits()) <= ulps)
    };
    let bad: Vec<usize> = (0..cpu.len().max(gpu.len()))
        .filter(|&i| match (cpu.get(i), gpu.get(i)) {
            (Some(a), Some(b)) => !close(a, b),
            _ => true,
        })
        .collect();
    match bad.first() {
        None => Ok(()),
        Some(&i) => Err(Mismatch {
            what: what.into(),
            index: i,
            expected: format!("{:?}", cpu.get(i)),
            found: format!("{:?}", gpu.get(i)),
            count: bad.len(),
            total: cpu.len().max(gpu.len()),
        }),
    }
}

/// The production CPU path (bit rows, per-layer counts, chunk stitching) is
/// the fast path beside the mirrors: the same vertices bit for bit, the
/// same triangles, cells and groups as the three mirrors chained, on every
/// fixture volume and on the real CT.
#[test]
fn mc_fast_cpu_path_equals_the_chained_mirrors() {
    use chisel::mc::{cpu, gpu};
    let mut cases = vec![
        (random_volume(1, [23, 17, 11]), IsoSpec::Level(1000.0)),
        (random_volume(5, [40, 30, 24]), IsoSpec::Level(1000.5)),
    ];
    if let Some(vol) = common::real_volume("headsq/quarter.nhdr") {
        cases.push((vol.clone(), IsoSpec::Level(500.0)));
        cases.push((vol, IsoSpec::Level(1150.0)));
    }
    for (vol, iso) in &cases {
        for close in [false, true] {
            let field = Field::new(vol, *iso, close).unwrap();
            let fast = cpu::marching_cubes(&field, true).unwrap();
            let mirrored = gpu::assemble(mirror::marching_cubes(&field).unwrap(), true);
            let what = format!("{iso:?} close {close}");
            assert!(!fast.triangles.is_empty(), "{what}");
            let bits = |p: &[[f32; 3]]| -> Vec<[u32; 3]> {
                p.iter().map(|v| v.map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&fast.positions), bits(&mirrored.positions), "{what}");
            assert_eq!(fast.edges, mirrored.edges, "{what}");
            assert_eq!(fast.triangles, mirrored.triangles, "{what}");
            assert_eq!(fast.cells, mirrored.cells, "{what}");
            assert_eq!(
                (&fast.groups, fast.n_groups),
                (&mirrored.groups, mirrored.n_groups),
                "{what}"
            );
        }
    }
}
