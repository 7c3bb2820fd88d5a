//! One dispatch of each marching-cubes kernel on explicit inputs, as its
//! mirror in [`crate::mc::mirror`] takes them: the entry points of the
//! per-kernel parity tests (`tests/parity/mc_*.rs`). The pipeline in
//! [`super`] binds the same kernels through the same `bind_*` functions.

use super::{
    ClassifyParams, InsideParams, TrianglesParams, VerticesParams, bind_classify, bind_inside,
    bind_triangles, bind_vertices,
};
use crate::Result;
use crate::gpu::{BoundKernel, Gpu, GpuArray, UniformBuffer};

/// Records `bound` over `n_blocks` blocks, submits, and reads `out` back.
fn run_blocks<T: bytemuck::Pod>(
    gpu: &Gpu,
    bound: &BoundKernel,
    n_blocks: u32,
    out: &GpuArray<T>,
) -> Result<Vec<T>> {
    let mut encoder = gpu.encoder(bound.kernel().name());
    bound.record(gpu, &mut encoder, n_blocks * bound.wg_size(), None);
    gpu.submit_and_wait(encoder)?;
    out.read(gpu)
}

/// One `mc_inside` dispatch on explicit inputs, as
/// [`crate::mc::mirror::mc_inside`] takes them (parity tests): the words of
/// `params.n_layers` layers of bit rows.
pub fn mc_inside(gpu: &Gpu, params: &InsideParams, samples: &[u32]) -> Result<Vec<u32>> {
    let n_words = (params.n_layers * params.grid.ny * params.row_words) as usize;
    let inside_bits = GpuArray::output(gpu, "mc_inside.inside_bits", n_words, u32::MAX)?;
    let uniform = UniformBuffer::new(gpu, "mc_inside.params", params)?;
    let samples = GpuArray::from_slice(gpu, "mc_inside.samples", samples)?;
    let bound = bind_inside(gpu, &uniform, &samples, &inside_bits)?;
    let mut encoder = gpu.encoder(bound.kernel().name());
    bound.record(gpu, &mut encoder, n_words as u32, None);
    gpu.submit_and_wait(encoder)?;
    inside_bits.read(gpu)
}

/// One `mc_classify` dispatch on explicit inputs, as
/// [`crate::mc::mirror::mc_classify`] takes them (parity tests): the counts of
/// `params.n_layers · params.blocks_per_layer` blocks.
pub fn mc_classify(
    gpu: &Gpu,
    params: &ClassifyParams,
    inside_bits: &[u32],
    table: &[u32],
) -> Result<Vec<[u32; 2]>> {
    let n_blocks = params.n_layers * params.blocks_per_layer;
    let counts = GpuArray::output(
        gpu,
        "mc_classify.block_counts",
        n_blocks as usize,
        [u32::MAX; 2],
    )?;
    let uniform = UniformBuffer::new(gpu, "mc_classify.params", params)?;
    let inside_bits = GpuArray::from_slice(gpu, "mc_classify.inside_bits", inside_bits)?;
    let table = GpuArray::from_slice(gpu, "mc_classify.table", table)?;
    let bound = bind_classify(gpu, &uniform, &table, &inside_bits, &counts)?;
    run_blocks(gpu, &bound, n_blocks, &counts)
}

/// One `mc_vertices` dispatch on explicit inputs, as
/// [`crate::mc::mirror::mc_vertices`] takes them: (`vert_base`, `positions`),
/// `vert_base` starting at zero, `positions` a kernel output of
/// `n_vertices` elements.
pub fn mc_vertices(
    gpu: &Gpu,
    params: &VerticesParams,
    samples: &[u32],
    inside_bits: &[u32],
    block_offsets: &[u32],
    n_vertices: usize,
) -> Result<(Vec<u32>, Vec<[f32; 4]>)> {
    let n_blocks = params.n_layers * params.blocks_per_layer;
    let layer = (params.grid.nx * params.grid.ny) as usize;
    let uniform = UniformBuffer::new(gpu, "mc_vertices.params", params)?;
    let samples = GpuArray::from_slice(gpu, "mc_vertices.samples", samples)?;
    let inside_bits = GpuArray::from_slice(gpu, "mc_vertices.inside_bits", inside_bits)?;
    let offsets = GpuArray::from_slice(gpu, "mc_vertices.block_offsets", block_offsets)?;
    let vert_base = GpuArray::zeroed(
        gpu,
        "mc_vertices.vert_base",
        params.n_layers as usize * layer,
    )?;
    let positions = GpuArray::output(gpu, "mc_vertices.positions", n_vertices, [f32::NAN; 4])?;
    let bound = bind_vertices(
        gpu,
        &uniform,
        &samples,
        &inside_bits,
        &offsets,
        &vert_base,
        &positions,
    )?;
    let positions = run_blocks(gpu, &bound, n_blocks, &positions)?;
    Ok((vert_base.read(gpu)?, positions))
}

/// One `mc_triangles` dispatch on explicit inputs, as
/// [`crate::mc::mirror::mc_triangles`] takes them: `n_triangles` triangles.
pub fn mc_triangles(
    gpu: &Gpu,
    params: &TrianglesParams,
    inside_bits: &[u32],
    table: &[u32],
    block_offsets: &[u32],
    vert_base: &[u32],
    n_triangles: usize,
) -> Result<Vec<[u32; 4]>> {
    let n_blocks = params.n_layers * params.blocks_per_layer;
    let uniform = UniformBuffer::new(gpu, "mc_triangles.params", params)?;
    let inside_bits = GpuArray::from_slice(gpu, "mc_triangles.inside_bits", inside_bits)?;
    let table = GpuArray::from_slice(gpu, "mc_triangles.table", table)?;
    let offsets = GpuArray::from_slice(gpu, "mc_triangles.block_offsets", block_offsets)?;
    let vert_base = GpuArray::from_slice(gpu, "mc_triangles.vert_base", vert_base)?;
    let triangles = GpuArray::output(gpu, "mc_triangles.triangles", n_triangles, [u32::MAX; 4])?;
    let bound = bind_triangles(
        gpu,
        &uniform,
        &table,
        &inside_bits,
        &offsets,
        &vert_base,
        &triangles,
    )?;
    run_blocks(gpu, &bound, n_blocks, &triangles)
}
