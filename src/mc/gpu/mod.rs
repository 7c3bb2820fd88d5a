//! GPU marching cubes: `mc_inside` → `mc_classify` → host exclusive scan of
//! the block sums → `mc_vertices` → `mc_triangles`, in slabs of z layers.
//!
//! Inside flags: `mc_inside` packs the inside flag of every point into bit
//! rows, the `inside_bits` ([`super::grid::BitRows`]: one read of each
//! sample, one bit kept), from which the other kernels find cases and
//! crossing edges; only `mc_vertices` reads samples again, at the two ends
//! of each crossing edge. With the samples resident (below) and the flags
//! of the whole grid within one binding, they are made once for both
//! passes; otherwise each slab makes its own, a classify slab for its
//! layers and the one above, an emission slab for its layers and the two
//! above.
//!
//! Scan: each kernel scans its own 256-point block in workgroup memory; the
//! host scans the per-block sums of the whole grid (one `u32` pair per 256
//! points, a 2 MiB readback for a 512³ volume) — no dependency on the
//! engine's generic scan kernels.
//!
//! Samples travel in the volume's own type ([`super::grid`]: 2 bytes a
//! sample for an `i16` CT, decoded, padded and compared with a label in the
//! kernels). When the whole volume fits one storage binding
//! ([`Gpu::max_binding_bytes`]; 2 GiB on an H200: about 1020³ `i16` or 810³
//! `f32` samples) it is uploaded once and stays resident for both passes;
//! otherwise each slab uploads its own layers. Pass 1 classifies slabs whose
//! samples fit one binding; pass 2 re-slabs knowing the exact per-layer
//! vertex and triangle counts, so that samples, inside flags, `vert_base`,
//! positions and triangles of a slab each fit one binding. `vert_base` is cleared on the
//! device (the vertex pass writes all of it); positions and triangles are
//! cleared on the device too, and start as sentinels only on a device
//! opened with sentinels (tests). Output is read back per slab; vertices and triangles come
//! out in the CPU mirror's order (point order, cell order), so the grouping
//! finishes on the host with the same union-find numbering. With timestamp
//! queries the kernels' GPU time is measured too ([`GpuRaw::kernel_seconds`]).

mod dispatch;

pub use dispatch::{mc_classify, mc_inside, mc_triangles, mc_vertices};

use super::cpu::RawSurface;
use super::field::Field;
use super::grid::{BitRows, SampleGrid, inner_layers, sample_bytes, sample_grid, sample_words};
use super::{exclusive_offsets, tables};
use crate::foundation::vertex_components;
use crate::gpu::{BoundKernel, Gpu, GpuArray, Kernel, PassTimer, UniformBuffer};
use crate::parity::find_sentinel;
use crate::{Error, Result};

/// Uniform parameters of `mc_inside`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct InsideParams {
    /// The padded grid and its sample words.
    pub grid: SampleGrid,
    pub z_begin: u32,
    pub n_layers: u32,
    /// Words a bit row ([`BitRows::row_words`]).
    pub row_words: u32,
}

/// Uniform parameters of `mc_classify`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct ClassifyParams {
    /// The padded grid and the layers of the inside flags.
    pub rows: BitRows,
    pub z_begin: u32,
    pub n_layers: u32,
    pub blocks_per_layer: u32,
}

/// Uniform parameters of `mc_vertices`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct VerticesParams {
    /// The padded grid and its sample words.
    pub grid: SampleGrid,
    /// The layers of the inside flags.
    pub rows: BitRows,
    pub z_begin: u32,
    pub n_layers: u32,
    pub n_owned: u32,
    pub blocks_per_layer: u32,
    pub v_start: u32,
}

/// Uniform parameters of `mc_triangles`.
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct TrianglesParams {
    /// The padded grid and the layers of the inside flags.
    pub rows: BitRows,
    pub z_begin: u32,
    pub n_layers: u32,
    pub blocks_per_layer: u32,
    pub vb_first: u32,
    pub t_start: u32,
}

/// Output of the GPU passes before host grouping, as read back.
#[derive(Debug, Clone, Default)]
pub struct GpuRaw {
    /// #V `[x, y, z, bitcast edge id]` in grid index space.
    pub positions: Vec<[f32; 4]>,
    /// #F `[v0, v1, v2, cell]`.
    pub triangles: Vec<[u32; 4]>,
    /// GPU-clock seconds of `mc_inside`, `mc_classify`, `mc_vertices` and
    /// `mc_triangles`, each summed over its dispatches (`mc_inside` once
    /// when the samples are resident, else per slab of both passes;
    /// timestamp queries; `None` when the device has none). Excludes
    /// uploads, readbacks and the host scan.
    pub kernel_seconds: Option<[f64; 4]>,
}

/// Marching cubes of `field` on the GPU, grouping finished on the host.
pub fn marching_cubes(gpu: &Gpu, field: &Field<'_>, grouping: bool) -> Result<RawSurface> {
    let raw = marching_cubes_raw(gpu, field)?;
    Ok(assemble(raw, grouping))
}

/// Turns read-back GPU output into a [`RawSurface`] (grouping on the host:
/// vertex-connected components numbered by first triangle, the same
/// partition and numbering as the CPU's one-pass grouping).
pub fn assemble(raw: GpuRaw, grouping: bool) -> RawSurface {
    let positions = raw.positions.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let edges = raw
        .positions
        .iter()
        .map(|p| u64::from(p[3].to_bits()))
        .collect();
    let triangles: Vec<[u32; 3]> = raw.triangles.iter().map(|t| [t[0], t[1], t[2]]).collect();
    let cells = raw.triangles.iter().map(|t| t[3]).collect();
    let (groups, n_groups) = if grouping {
        vertex_components(raw.positions.len(), &triangles)
    } else {
        (Vec::new(), 0)
    };
    let vertex_groups = if grouping {
        super::vertex_groups(raw.positions.len(), &triangles, &groups)
    } else {
        Vec::new()
    };
    RawSurface {
        positions,
        edges,
        triangles,
        cells,
        groups,
        vertex_groups,
        n_groups,
    }
}

/// The passes. On a device with sentinels on
/// ([`crate::gpu::GpuOptions::sentinels`]) output buffers start as NaN /
/// `u32::MAX` and any survivor is an error.
pub fn marching_cubes_raw(gpu: &Gpu, field: &Field<'_>) -> Result<GpuRaw> {
    let [nx, ny, nz] = field.dims;
    if field.dims.iter().any(|&d| d < 2) {
        return Ok(GpuRaw::default());
    }
    field.check_finite()?;
    if (field.n_points() as u64) * 3 > u64::from(u32::MAX) {
        return Err(Error::limit(
            format!(
                "GPU marching cubes: grid edges of grid {:?} (u32 numbering)",
                field.dims
            ),
            field.n_points().saturating_mul(3),
            u32::MAX,
        ));
    }
    let layer = nx * ny;
    // Blocks per layer: one workgroup of all three kernels a block.
    let bpl = layer.div_ceil(Kernel::McClassify.spec()?.wg_size as usize);
    let max = gpu.max_binding_bytes();
    let layer_bytes = (layer * 4) as u64;
    // Bytes of the sample words of `n` padded layers (a bound: the words
    // hold inner layers, which are no larger).
    let sample_layer_bytes = (layer * sample_bytes(field)) as u64;
    let samples_bytes = |n: usize| (n as u64 * sample_layer_bytes).next_multiple_of(4);
    // Bytes of the inside flags of `n` layers.
    let bits_layer_bytes = BitRows::new(field, 0).words(1) as u64 * 4;
    let bits_bytes = |n: usize| n as u64 * bits_layer_bytes;
    // A classify slab holds its layers plus one above.
    let classify_layers =
        (max / sample_layer_bytes.max(bits_layer_bytes)).saturating_sub(1) as usize;
    if classify_layers == 0 {
        return Err(Error::limit(
            "marching cubes: bytes of two sample or inside-flag layers (one storage binding)",
            samples_bytes(2).max(bits_bytes(2)),
            max,
        ));
    }
    let table = GpuArray::from_slice(gpu, "mc.table", &tables::table().flat())?;
    let dims = [nx as u32, ny as u32, nz as u32];
    let resident = if samples_bytes(nz) <= max {
        Some(upload_layers(gpu, field, 0, field.volume().dims[2])?)
    } else {
        None
    };
    let mut kernel_seconds = gpu.features.timestamps.then_some([0.0; 4]);
    // Pass times of kernels `which` (0 `mc_inside`, 1 `mc_classify`, 2
    // `mc_vertices`, 3 `mc_triangles`), added to their sums.
    let mut add_time = |which: &[usize], t: Option<Vec<f64>>| {
        if let (Some(sums), Some(t)) = (kernel_seconds.as_mut(), t) {
            for (&k, t) in which.iter().zip(t) {
                sums[k] += t;
            }
        }
    };

    // The inside flags of the whole grid, made once for both passes when
    // the samples are resident and the flags fit one binding; else each
    // slab makes its own (`make`), first of its passes.
    let resident_bits = match &resident {
        Some(all) if bits_bytes(nz) <= max => {
            let samples = Samples {
                buffer: all,
                grid: sample_grid(field, 0),
            };
            let bits = InsideBits::new(gpu, field, samples, 0, nz)?;
            add_time(&[0], bits.make(gpu)?);
            Some(bits)
        }
        _ => None,
    };
    let make = resident_bits.is_none();
    // The kernels timed in a slab's submission: `mc_inside` first if made.
    let timed = |kernels: &'static [usize]| &kernels[usize::from(!make)..];

    // Pass 1: block sums of the whole grid.
    let mut counts: Vec<[u32; 2]> = Vec::with_capacity(nz * bpl);
    let mut a = 0;
    while a < nz {
        let b = (a + classify_layers).min(nz);
        let mut slot = None;
        let samples = Samples::get(resident.as_ref(), &mut slot, gpu, field, a, (b + 1).min(nz))?;
        let mut own = None;
        let bits = InsideBits::get(
            resident_bits.as_ref(),
            &mut own,
            gpu,
            field,
            samples,
            a,
            b + 1,
        )?;
        let (c, t) = classify(gpu, &table, bits, make, a, b - a, bpl)?;
        counts.extend(c);
        add_time(timed(&[0, 1]), t);
        a = b;
    }

    // Host exclusive scan of the block sums.
    let off_v = exclusive_offsets(counts.iter().map(|c| c[0].into()), "vertices")?;
    let off_t = exclusive_offsets(counts.iter().map(|c| c[1].into()), "triangles")?;
    let per_layer = |z: usize, k: usize| -> u64 {
        counts[z * bpl..(z + 1) * bpl]
            .iter()
            .map(|c| u64::from(c[k]))
            .sum()
    };
    let layer_v: Vec<u64> = (0..nz).map(|z| per_layer(z, 0)).collect();
    let layer_t: Vec<u64> = (0..nz).map(|z| per_layer(z, 1)).collect();

    // Pass 2: emission slabs [a, b) of point layers.
    let mut out = GpuRaw {
        positions: Vec::with_capacity(off_v[nz * bpl] as usize),
        triangles: Vec::with_capacity(off_t[nz * bpl] as usize),
        kernel_seconds: None,
    };
    let fits = |a: usize, b: usize| -> bool {
        let samples = samples_bytes((b + 2).min(nz) - a);
        let vert_base = ((b + 1).min(nz) - a) as u64 * layer_bytes;
        let verts: u64 = layer_v[a..b].iter().sum::<u64>() * 16;
        let tris: u64 = layer_t[a..b.min(nz - 1)].iter().sum::<u64>() * 16;
        let bits = if make {
            bits_bytes((b + 2).min(nz) - a)
        } else {
            0
        };
        samples <= max && bits <= max && vert_base <= max && verts <= max && tris <= max
    };
    let mut a = 0;
    while a < nz {
        let mut b = a + 1;
        if !fits(a, b) {
            return Err(Error::limit(
                format!("marching cubes: bytes of layer {a} (one storage binding)"),
                u64::MAX,
                max,
            ));
        }
        while b < nz && fits(a, b + 1) {
            b += 1;
        }
        let slab = Slab {
            a,
            b,
            v_start: off_v[a * bpl],
            t_start: off_t[a * bpl],
            n_v: layer_v[a..b].iter().sum::<u64>() as usize,
            n_t: layer_t[a..b.min(nz - 1)].iter().sum::<u64>() as usize,
        };
        let mut slot = None;
        let samples = Samples::get(resident.as_ref(), &mut slot, gpu, field, a, (b + 2).min(nz))?;
        let mut own = None;
        let bits = InsideBits::get(
            resident_bits.as_ref(),
            &mut own,
            gpu,
            field,
            samples,
            a,
            b + 2,
        )?;
        let (p, t, seconds) = emit(
            gpu, samples, bits, make, &table, dims, bpl, &off_v, &off_t, &slab,
        )?;
        out.positions.extend(p);
        out.triangles.extend(t);
        add_time(timed(&[0, 2, 3]), seconds);
        a = b;
    }
    out.kernel_seconds = kernel_seconds;
    Ok(out)
}

/// A buffer of sample words ([`super::grid`]) and the grid that reads it.
#[derive(Clone, Copy)]
struct Samples<'a> {
    buffer: &'a GpuArray<u32>,
    grid: SampleGrid,
}

impl<'a> Samples<'a> {
    /// The resident grid, or else the inner layers of padded layers
    /// `z0..z1` uploaded into `slot`.
    fn get(
        resident: Option<&'a GpuArray<u32>>,
        slot: &'a mut Option<GpuArray<u32>>,
        gpu: &Gpu,
        field: &Field<'_>,
        z0: usize,
        z1: usize,
    ) -> Result<Self> {
        Ok(match resident {
            Some(all) => Samples {
                buffer: all,
                grid: sample_grid(field, 0),
            },
            None => {
                let (k0, k1) = inner_layers(field, z0, z1);
                Samples {
                    buffer: slot.insert(upload_layers(gpu, field, k0, k1)?),
                    grid: sample_grid(field, k0),
                }
            }
        })
    }
}

/// Point layers `a..b` of one emission slab and its output ranges.
struct Slab {
    a: usize,
    b: usize,
    v_start: u32,
    t_start: u32,
    n_v: usize,
    n_t: usize,
}

/// The inside flags of padded layers `z0..z1` (`mc_inside`'s
/// `inside_bits`), bound and ready to record: the words and the rows that
/// read them.
struct InsideBits {
    rows: BitRows,
    words: GpuArray<u32>,
    bound: BoundKernel,
}

impl InsideBits {
    /// The resident flags, or else those of padded layers `z0..z1` (clipped
    /// at the grid's end) made from `samples` into `slot`.
    fn get<'a>(
        resident: Option<&'a InsideBits>,
        slot: &'a mut Option<InsideBits>,
        gpu: &Gpu,
        field: &Field<'_>,
        samples: Samples<'_>,
        z0: usize,
        z1: usize,
    ) -> Result<&'a InsideBits> {
        Ok(match resident {
            Some(bits) => bits,
            None => slot.insert(InsideBits::new(
                gpu,
                field,
                samples,
                z0,
                z1.min(field.dims[2]),
            )?),
        })
    }

    fn new(
        gpu: &Gpu,
        field: &Field<'_>,
        samples: Samples<'_>,
        z0: usize,
        z1: usize,
    ) -> Result<Self> {
        let rows = BitRows::new(field, z0);
        let params = UniformBuffer::new(
            gpu,
            "mc_inside.params",
            &InsideParams {
                grid: samples.grid,
                z_begin: z0 as u32,
                n_layers: (z1 - z0) as u32,
                row_words: rows.row_words,
            },
        )?;
        // Every word is written by the kernel.
        let words = GpuArray::zeroed(gpu, "mc_inside.inside_bits", rows.words(z1 - z0))?;
        let bound = bind_inside(gpu, &params, samples.buffer, &words)?;
        Ok(InsideBits { rows, words, bound })
    }

    /// Records the `mc_inside` pass (one invocation per word).
    fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<(&PassTimer, u32)>,
    ) {
        self.bound
            .record(gpu, encoder, self.words.len() as u32, timer);
    }

    /// Runs the `mc_inside` pass on its own; its GPU seconds.
    fn make(&self, gpu: &Gpu) -> Result<PassSeconds> {
        let timer = gpu.pass_timer(1);
        let mut encoder = gpu.encoder("mc_inside");
        self.record(gpu, &mut encoder, timer.as_ref().map(|t| (t, 0)));
        let times = timer.map(|t| t.stage(gpu, &mut encoder)).transpose()?;
        gpu.submit_and_wait(encoder)?;
        times.map(|t| t.finish(gpu)).transpose()
    }
}

/// Inner layers `k0..k1` as one storage buffer of sample words.
fn upload_layers(gpu: &Gpu, field: &Field<'_>, k0: usize, k1: usize) -> Result<GpuArray<u32>> {
    GpuArray::from_slice(gpu, "mc.samples", &sample_words(field, k0, k1)?)
}

/// The block counts of layers `z_begin..z_begin + n_layers` from
/// `inside_bits` (made first when `make`), and the GPU seconds of the
/// passes (`mc_inside` when made, `mc_classify`).
fn classify(
    gpu: &Gpu,
    table: &GpuArray<u32>,
    inside_bits: &InsideBits,
    make: bool,
    z_begin: usize,
    n_layers: usize,
    bpl: usize,
) -> Result<(Vec<[u32; 2]>, PassSeconds)> {
    let kernel = Kernel::McClassify;
    let n_blocks = n_layers * bpl;
    let params = UniformBuffer::new(
        gpu,
        "mc_classify.params",
        &ClassifyParams {
            rows: inside_bits.rows,
            z_begin: z_begin as u32,
            n_layers: n_layers as u32,
            blocks_per_layer: bpl as u32,
        },
    )?;
    let counts = GpuArray::output(gpu, "mc_classify.block_counts", n_blocks, [u32::MAX; 2])?;
    let bound = bind_classify(gpu, &params, table, &inside_bits.words, &counts)?;
    let made = u32::from(make);
    let timer = gpu.pass_timer(made + 1);
    let mut encoder = gpu.encoder("mc_classify");
    let at = |i| timer.as_ref().map(|t| (t, i));
    if make {
        inside_bits.record(gpu, &mut encoder, at(0));
    }
    let n_invocations = n_blocks as u32 * bound.wg_size();
    bound.record(gpu, &mut encoder, n_invocations, at(made));
    let times = timer.map(|t| t.stage(gpu, &mut encoder)).transpose()?;
    let staged = counts.stage(gpu, &mut encoder)?;
    gpu.submit_and_wait(encoder)?;
    let out = staged.finish(gpu)?;
    if gpu.sentinels()
        && let Some(i) = find_sentinel(&out, [u32::MAX; 2])
    {
        return Err(sentinel(kernel, i));
    }
    Ok((out, times.map(|t| t.finish(gpu)).transpose()?))
}

fn sentinel(kernel: Kernel, index: usize) -> Error {
    Error::Kernel {
        name: kernel.name().into(),
        message: format!("output element {index} was never written (sentinel survived)"),
    }
}

/// GPU seconds of each pass of one submission (with timestamp queries).
type PassSeconds = Option<Vec<f64>>;

/// Positions, triangles and the kernels' GPU seconds of one slab
/// (`mc_inside` when made, `mc_vertices`, `mc_triangles`).
type SlabOutput = (Vec<[f32; 4]>, Vec<[u32; 4]>, PassSeconds);

/// The vertices and triangles of one emission slab from its samples and
/// `inside_bits` (made first when `make`).
#[expect(
    clippy::too_many_arguments,
    reason = "the passes of one slab sharing its buffers"
)]
fn emit(
    gpu: &Gpu,
    samples: Samples<'_>,
    inside_bits: &InsideBits,
    make: bool,
    table: &GpuArray<u32>,
    dims: [u32; 3],
    bpl: usize,
    off_v: &[u32],
    off_t: &[u32],
    slab: &Slab,
) -> Result<SlabOutput> {
    let nz = dims[2] as usize;
    let (a, b) = (slab.a, slab.b);
    let vb_layers = (b + 1).min(nz) - a;
    let cell_layers = b.min(nz - 1).saturating_sub(a);
    let layer = (dims[0] * dims[1]) as usize;
    // Each slab's offsets and the next one (the kernels take a block's
    // count as the difference).
    let offsets_v = GpuArray::from_slice(
        gpu,
        "mc_vertices.block_offsets",
        &off_v[a * bpl..=(a + vb_layers) * bpl],
    )?;
    let offsets_t = GpuArray::from_slice(
        gpu,
        "mc_triangles.block_offsets",
        &off_t[a * bpl..=(a + cell_layers.max(1)) * bpl],
    )?;
    let vert_base = GpuArray::<u32>::zeroed(gpu, "mc_vertices.vert_base", vb_layers * layer)?;
    let positions = GpuArray::output(gpu, "mc_vertices.positions", slab.n_v, [f32::NAN; 4])?;
    let triangles = GpuArray::output(gpu, "mc_triangles.triangles", slab.n_t, [u32::MAX; 4])?;
    let vparams = UniformBuffer::new(
        gpu,
        "mc_vertices.params",
        &VerticesParams {
            grid: samples.grid,
            rows: inside_bits.rows,
            z_begin: a as u32,
            n_layers: vb_layers as u32,
            n_owned: (b - a) as u32,
            blocks_per_layer: bpl as u32,
            v_start: slab.v_start,
        },
    )?;
    let tparams = UniformBuffer::new(
        gpu,
        "mc_triangles.params",
        &TrianglesParams {
            rows: inside_bits.rows,
            z_begin: a as u32,
            n_layers: cell_layers as u32,
            blocks_per_layer: bpl as u32,
            vb_first: a as u32,
            t_start: slab.t_start,
        },
    )?;
    let vk = Kernel::McVertices;
    let tk = Kernel::McTriangles;
    let vbound = bind_vertices(
        gpu,
        &vparams,
        samples.buffer,
        &inside_bits.words,
        &offsets_v,
        &vert_base,
        &positions,
    )?;
    let tbound = bind_triangles(
        gpu,
        &tparams,
        table,
        &inside_bits.words,
        &offsets_t,
        &vert_base,
        &triangles,
    )?;
    let made = u32::from(make);
    let timer = gpu.pass_timer(made + 2);
    let mut encoder = gpu.encoder("mc_emit");
    let at = |i| timer.as_ref().map(|t| (t, i));
    if make {
        inside_bits.record(gpu, &mut encoder, at(0));
    }
    let n_v = (vb_layers * bpl) as u32 * vbound.wg_size();
    vbound.record(gpu, &mut encoder, n_v, at(made));
    let n_t = (cell_layers * bpl) as u32 * tbound.wg_size();
    tbound.record(gpu, &mut encoder, n_t, at(made + 1));
    let staged_p = positions.stage(gpu, &mut encoder)?;
    let staged_t = triangles.stage(gpu, &mut encoder)?;
    let times = timer.map(|t| t.stage(gpu, &mut encoder)).transpose()?;
    gpu.submit_and_wait(encoder)?;
    let p = staged_p.finish(gpu)?;
    let t = staged_t.finish(gpu)?;
    if gpu.sentinels() {
        if let Some(i) = p.iter().position(|v| v[..3].iter().any(|c| c.is_nan())) {
            return Err(sentinel(vk, i));
        }
        if let Some(i) = find_sentinel(&t, [u32::MAX; 4]) {
            return Err(sentinel(tk, i));
        }
    }
    Ok((p, t, times.map(|t| t.finish(gpu)).transpose()?))
}

fn bind_inside(
    gpu: &Gpu,
    params: &UniformBuffer<InsideParams>,
    samples: &GpuArray<u32>,
    inside_bits: &GpuArray<u32>,
) -> Result<BoundKernel> {
    (gpu.kernel(Kernel::McInside)?)
        .uniform(params)
        .read(samples)
        .write(inside_bits)
        .bind()
}

fn bind_classify(
    gpu: &Gpu,
    params: &UniformBuffer<ClassifyParams>,
    table: &GpuArray<u32>,
    inside_bits: &GpuArray<u32>,
    block_counts: &GpuArray<[u32; 2]>,
) -> Result<BoundKernel> {
    (gpu.kernel(Kernel::McClassify)?)
        .uniform(params)
        .read(table)
        .read(inside_bits)
        .write(block_counts)
        .bind()
}

fn bind_vertices(
    gpu: &Gpu,
    params: &UniformBuffer<VerticesParams>,
    samples: &GpuArray<u32>,
    inside_bits: &GpuArray<u32>,
    block_offsets: &GpuArray<u32>,
    vert_base: &GpuArray<u32>,
    positions: &GpuArray<[f32; 4]>,
) -> Result<BoundKernel> {
    (gpu.kernel(Kernel::McVertices)?)
        .uniform(params)
        .read(samples)
        .read(inside_bits)
        .read(block_offsets)
        .write(vert_base)
        .write(positions)
        .bind()
}

fn bind_triangles(
    gpu: &Gpu,
    params: &UniformBuffer<TrianglesParams>,
    table: &GpuArray<u32>,
    inside_bits: &GpuArray<u32>,
    block_offsets: &GpuArray<u32>,
    vert_base: &GpuArray<u32>,
    triangles: &GpuArray<[u32; 4]>,
) -> Result<BoundKernel> {
    (gpu.kernel(Kernel::McTriangles)?)
        .uniform(params)
        .read(table)
        .read(inside_bits)
        .read(block_offsets)
        .read(vert_base)
        .write(triangles)
        .bind()
}
