//! GPU passes for `kernels/hull_scan.wgsl` / `hull_scan_i32x2.wgsl`
//! (every voxel) and `kernels/hull_rows.wgsl` / `hull_rows_i32x2.wgsl`
//! (per-row intervals). With `SHADER_INT64` the i64 kernels run, otherwise
//! their exact emulated twins ([`Arithmetic`]). The row kernels read per z
//! layer the list of faces to test: every face, or with the faces' z
//! ranges ([`HullScanInput::culled`]) only those meeting the layer, as
//! `hull_scan::cpu::hull_rows_culled` does. Boxes larger than one storage
//! binding ([`Gpu::max_binding_bytes`]) are processed in z slabs, one
//! dispatch and readback per slab; outputs start filled with sentinels
//! ([`SCAN_SENTINEL`], [`ROWS_SENTINEL`]) so a missed write shows.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};

use super::{Classification, HalfSpace, RowSpan, RowSpans, VoxelBox, check_range, cpu::i32x2};
use crate::gpu::{Gpu, GpuArray, Kernel, UniformBuffer};
use crate::{Error, Result};

/// Bytes of one slab's output at most, below the binding limit, so that
/// every index stays within `u32` in the kernels.
const MAX_SLAB_BYTES: u64 = 1 << 30;

/// Each `hull_scan*` output word before the kernel writes it (byte 0xFF is
/// no side code).
pub const SCAN_SENTINEL: u32 = u32::MAX;

/// Each `hull_rows*` output span before the kernel writes it.
pub const ROWS_SENTINEL: RowSpan = [i32::MIN; 4];

/// Uniform parameters of all four kernels (`kernels/shared/hull_face.wgsl`).
#[derive(Debug, Clone, Copy, encase::ShaderType)]
pub struct Params {
    /// Faces uploaded.
    pub n_faces: u32,
    /// Voxels (`hull_scan*`) or rows (`hull_rows*`) in this slab.
    pub n_items: u32,
    /// Voxels per row.
    pub nx: u32,
    /// Rows per z layer.
    pub ny: u32,
    /// First local z layer of the slab.
    pub z0: u32,
    /// Voxel index of the box's first voxel, per axis.
    pub origin_x: i32,
    pub origin_y: i32,
    pub origin_z: i32,
}

/// Start of a layer's face list when the polyhedron misses the layer
/// (`LAYER_MISSES` in `kernels/shared/hull_face.wgsl`).
pub const LAYER_MISSES: u32 = u32::MAX;

/// One face as the kernels read it (`struct Face`, 32 bytes): normal
/// `[n_x, n_y, n_z, 0]`, offset `[low word, high word, 0, 0]` of `d`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuFace {
    pub normal: [i32; 4],
    pub offset: [u32; 4],
}

impl GpuFace {
    /// Packs `h`; the caller has run [`check_range`] (normals fit `i32`).
    fn new(h: &HalfSpace) -> Self {
        let [lo, hi] = i32x2::from_i64(h.offset);
        GpuFace {
            normal: [
                h.normal[0] as i32,
                h.normal[1] as i32,
                h.normal[2] as i32,
                0,
            ],
            offset: [lo, hi, 0, 0],
        }
    }
}

/// Which integer arithmetic the kernels use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arithmetic {
    /// Native i64 (`SHADER_INT64`): `hull_scan`, `hull_rows`.
    Int64,
    /// Exact 64-bit pairs of u32 words: `hull_scan_i32x2`, `hull_rows_i32x2`.
    I32x2,
}

impl Arithmetic {
    /// Native i64 when the device has `SHADER_INT64`, else the fallback.
    pub fn of(gpu: &Gpu) -> Self {
        if gpu.features.int64 {
            Arithmetic::Int64
        } else {
            Arithmetic::I32x2
        }
    }

    /// The brute-force kernel.
    pub fn scan_kernel(self) -> Kernel {
        match self {
            Arithmetic::Int64 => Kernel::HullScan,
            Arithmetic::I32x2 => Kernel::HullScanI32x2,
        }
    }

    /// The per-row kernel.
    pub fn rows_kernel(self) -> Kernel {
        match self {
            Arithmetic::Int64 => Kernel::HullRows,
            Arithmetic::I32x2 => Kernel::HullRowsI32x2,
        }
    }
}

/// Consecutive z ranges whose output (`layer_bytes` per layer, plus up to
/// `pad` bytes) fits one binding.
fn slabs(gpu: &Gpu, nz: usize, layer_bytes: u64, pad: u64) -> Result<Vec<Range<usize>>> {
    let cap = gpu.max_binding_bytes().min(MAX_SLAB_BYTES);
    let layers = cap.saturating_sub(pad) / layer_bytes.max(1);
    if layers == 0 {
        return Err(Error::limit(
            "hull scan: bytes of one z layer (one storage binding)",
            layer_bytes + pad,
            cap,
        ));
    }
    let per = usize::try_from(layers).unwrap_or(usize::MAX);
    Ok((0..nz.div_ceil(per))
        .map(|s| s * per..((s + 1) * per).min(nz))
        .collect())
}

/// Consecutive z ranges of the row kernels: each slab's spans (`ny` per
/// layer) fit `cap` bytes, and so does its face-list buffer (two words per
/// layer, `ids[k]` face ids for layer `k`, plus `shared` ids stored once
/// per slab).
fn row_slabs(cap: u64, ny: usize, ids: &[u64], shared: u64) -> Result<Vec<Range<usize>>> {
    let layer_bytes = ny as u64 * std::mem::size_of::<RowSpan>() as u64;
    let mut out = Vec::new();
    let (mut start, mut span_bytes, mut words) = (0, 0, shared);
    for (k, &n) in ids.iter().enumerate() {
        let fits = |s: u64, w: u64| s <= cap && 4 * w <= cap;
        if k > start && !fits(span_bytes + layer_bytes, words + 2 + n) {
            out.push(start..k);
            (start, span_bytes, words) = (k, 0, shared);
        }
        span_bytes += layer_bytes;
        words += 2 + n;
        if !fits(span_bytes, words) {
            return Err(Error::limit(
                "hull scan: bytes of the spans or face lists of one z layer (one storage binding)",
                span_bytes.max(4 * words),
                cap,
            ));
        }
    }
    if start < ids.len() {
        out.push(start..ids.len());
    }
    Ok(out)
}

fn to_u32(what: &str, v: usize) -> Result<u32> {
    u32::try_from(v).map_err(|_| Error::limit(format!("hull scan: {what}"), v, u32::MAX))
}

/// Uploaded faces and the box, shared by the slabs of one scan.
#[derive(Debug)]
pub struct HullScanInput {
    faces: GpuArray<GpuFace>,
    n_faces: u32,
    bbox: VoxelBox,
    /// With [`HullScanInput::culled`]: the local z layers each face meets,
    /// and the layers the polytope misses.
    culling: Option<Culling>,
}

/// The z ranges of the faces in local layers of the box.
#[derive(Debug)]
struct Culling {
    /// Per face, the local layers `[first, last]` it meets, if any.
    layers: Vec<Option<[usize; 2]>>,
    /// Per local layer, whether it lies outside every face's range.
    misses: Vec<bool>,
}

impl Culling {
    /// From one inclusive combinatorial z range per face; layer `k` sits at
    /// `z = 2·(origin_z + k) + 1`.
    fn new(z_extents: &[[i64; 2]], bbox: &VoxelBox) -> Self {
        let nz = bbox.dims[2];
        let oz = bbox.origin[2];
        // First and last k with e0 ≤ 2·(oz + k) + 1 ≤ e1 (i128: any i64
        // range is accepted).
        let local = |[e0, e1]: [i64; 2]| {
            let o = 2 * i128::from(oz);
            let first = (i128::from(e0) - o).div_euclid(2).max(0);
            let last = (i128::from(e1) - 1 - o).div_euclid(2).min(nz as i128 - 1);
            (first <= last).then_some([first as usize, last as usize])
        };
        let range = z_extents.iter().fold([i64::MAX, i64::MIN], |r, e| {
            [r[0].min(e[0]), r[1].max(e[1])]
        });
        Culling {
            layers: z_extents.iter().map(|&e| local(e)).collect(),
            misses: (0..nz)
                .map(|k| {
                    let z = 2 * (oz + k as i64) + 1;
                    z < range[0] || z > range[1]
                })
                .collect(),
        }
    }

    /// Faces per local layer.
    fn counts(&self) -> Vec<u64> {
        let mut diff = vec![0i64; self.misses.len() + 1];
        for &[a, b] in self.layers.iter().flatten() {
            diff[a] += 1;
            diff[b + 1] -= 1;
        }
        let mut run = 0;
        diff[..self.misses.len()]
            .iter()
            .map(|d| {
                run += d;
                run as u64
            })
            .collect()
    }

    /// The `layers` buffer of slab `zs`: per layer its list's start and
    /// end (or [`LAYER_MISSES`]), then the lists, faces ascending.
    fn lists(&self, zs: &Range<usize>, counts: &[u64]) -> Vec<u32> {
        let header = 2 * zs.len();
        let total: u64 = counts[zs.clone()].iter().sum();
        let mut out = vec![0u32; header + total as usize];
        let mut cursor = Vec::with_capacity(zs.len());
        let mut at = header;
        for (i, k) in zs.clone().enumerate() {
            let n = counts[k] as usize;
            (out[2 * i], out[2 * i + 1]) = if self.misses[k] {
                (LAYER_MISSES, LAYER_MISSES)
            } else {
                (at as u32, (at + n) as u32)
            };
            cursor.push(at);
            at += n;
        }
        for (f, r) in self.layers.iter().enumerate() {
            let Some([a, b]) = *r else { continue };
            for k in a.max(zs.start)..=b.min(zs.end - 1) {
                let c = &mut cursor[k - zs.start];
                out[*c] = f as u32;
                *c += 1;
            }
        }
        out
    }
}

impl HullScanInput {
    /// Checks the range and uploads the faces.
    pub fn upload(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<Self> {
        check_range(half_spaces, bbox)?;
        let packed: Vec<GpuFace> = half_spaces.iter().map(GpuFace::new).collect();
        Ok(HullScanInput {
            faces: GpuArray::from_slice(gpu, "hull_scan.faces", &packed)?,
            n_faces: to_u32("faces", packed.len())?,
            bbox: *bbox,
            culling: None,
        })
    }

    /// Lets the row kernels test, per z layer, only the faces whose
    /// combinatorial z range (`z_extents[f]`, inclusive, one per face of a
    /// convex polytope) holds it, and leave layers outside every range
    /// empty: the spans of `hull_scan::cpu::hull_rows_culled`.
    ///
    /// Errors: not one range per face.
    pub fn culled(mut self, z_extents: &[[i64; 2]]) -> Result<Self> {
        if z_extents.len() != self.n_faces as usize {
            return Err(Error::mismatch(
                "hull scan: z ranges (one per face)",
                self.n_faces as usize,
                z_extents.len(),
            ));
        }
        self.culling = Some(Culling::new(z_extents, &self.bbox));
        Ok(self)
    }

    fn params(&self, n_items: usize, z0: usize) -> Result<Params> {
        let [nx, ny, _] = self.bbox.dims;
        // check_range keeps the origin within ±2^15.
        let o = self.bbox.origin.map(|v| v as i32);
        Ok(Params {
            n_faces: self.n_faces,
            n_items: to_u32("slab items", n_items)?,
            nx: to_u32("nx", nx)?,
            ny: to_u32("ny", ny)?,
            z0: to_u32("z0", z0)?,
            origin_x: o[0],
            origin_y: o[1],
            origin_z: o[2],
        })
    }

    /// Dispatches `kernel` over `n_invocations` into a fresh output of
    /// `out_len` elements (a kernel output, [`GpuArray::output`]) and reads
    /// it back; `lists`: the row kernels' face lists.
    #[expect(
        clippy::too_many_arguments,
        reason = "one per binding and dispatch size"
    )]
    fn run<T: Pod>(
        &self,
        gpu: &Gpu,
        kernel: Kernel,
        params: &Params,
        n_invocations: u32,
        out_len: usize,
        sentinel: T,
        lists: Option<&[u32]>,
    ) -> Result<Vec<T>> {
        let name = kernel.name();
        let uniform = UniformBuffer::new(gpu, &format!("{name}.params"), params)?;
        let out = GpuArray::output(gpu, &format!("{name}.out"), out_len, sentinel)?;
        let lists = lists
            .map(|l| GpuArray::from_slice(gpu, &format!("{name}.layers"), l))
            .transpose()?;
        let mut binder = gpu.kernel(kernel)?.uniform(&uniform).read(&self.faces);
        if let Some(lists) = &lists {
            binder = binder.read(lists);
        }
        let bound = binder.write(&out).bind()?;
        let mut encoder = gpu.encoder(name);
        bound.record(gpu, &mut encoder, n_invocations, None);
        gpu.submit_and_wait(encoder)?;
        out.read(gpu)
    }

    /// Side codes of every voxel with `arithmetic`'s brute-force kernel,
    /// slab by slab.
    pub fn scan(&self, gpu: &Gpu, arithmetic: Arithmetic) -> Result<Classification> {
        let n = self.bbox.n_voxels()?;
        let [nx, ny, nz] = self.bbox.dims;
        let mut sides = Vec::with_capacity(n);
        if n > 0 {
            for zs in slabs(gpu, nz, (nx * ny) as u64, 4)? {
                let n_voxels = nx * ny * zs.len();
                let n_words = n_voxels.div_ceil(4);
                let params = self.params(n_voxels, zs.start)?;
                let words = self.run(
                    gpu,
                    arithmetic.scan_kernel(),
                    &params,
                    to_u32("words", n_words)?,
                    n_words,
                    SCAN_SENTINEL,
                    None,
                )?;
                sides.extend_from_slice(&bytemuck::cast_slice::<u32, u8>(&words)[..n_voxels]);
            }
        }
        Ok(Classification {
            bbox: self.bbox,
            sides,
        })
    }

    /// Per-row spans with `arithmetic`'s row kernel, slab by slab.
    pub fn rows(&self, gpu: &Gpu, arithmetic: Arithmetic) -> Result<RowSpans> {
        let [_, ny, nz] = self.bbox.dims;
        let mut spans = Vec::with_capacity(self.bbox.n_rows());
        if ny > 0 && nz > 0 {
            // Every face, stored once per slab, or per layer its own list.
            let (counts, shared) = match &self.culling {
                Some(c) => (c.counts(), 0),
                None => (vec![0; nz], u64::from(self.n_faces)),
            };
            let cap = gpu.max_binding_bytes().min(MAX_SLAB_BYTES);
            for zs in row_slabs(cap, ny, &counts, shared)? {
                let lists = match &self.culling {
                    Some(c) => c.lists(&zs, &counts),
                    None => {
                        let start = 2 * zs.len() as u32;
                        let header = [start, start + self.n_faces].repeat(zs.len());
                        header.into_iter().chain(0..self.n_faces).collect()
                    }
                };
                let n_rows = ny * zs.len();
                let params = self.params(n_rows, zs.start)?;
                spans.extend(self.run(
                    gpu,
                    arithmetic.rows_kernel(),
                    &params,
                    to_u32("rows", n_rows)?,
                    n_rows,
                    ROWS_SENTINEL,
                    Some(&lists),
                )?);
            }
        }
        Ok(RowSpans {
            bbox: self.bbox,
            spans,
        })
    }
}

/// Brute-force classification on the GPU (arithmetic by device features).
pub fn hull_scan(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<Classification> {
    HullScanInput::upload(gpu, half_spaces, bbox)?.scan(gpu, Arithmetic::of(gpu))
}

/// Per-row spans on the GPU (arithmetic by device features).
pub fn hull_rows(gpu: &Gpu, half_spaces: &[HalfSpace], bbox: &VoxelBox) -> Result<RowSpans> {
    HullScanInput::upload(gpu, half_spaces, bbox)?.rows(gpu, Arithmetic::of(gpu))
}

/// [`hull_rows`] testing per z layer only the faces whose z range holds it
/// ([`HullScanInput::culled`]).
pub fn hull_rows_culled(
    gpu: &Gpu,
    half_spaces: &[HalfSpace],
    z_extents: &[[i64; 2]],
    bbox: &VoxelBox,
) -> Result<RowSpans> {
    HullScanInput::upload(gpu, half_spaces, bbox)?
        .culled(z_extents)?
        .rows(gpu, Arithmetic::of(gpu))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_slabs_fit_spans_and_lists() {
        // 8 rows: 128 bytes of spans per layer.
        assert_eq!(
            row_slabs(1024, 8, &[0; 20], 0).unwrap(),
            [0..8, 8..16, 16..20]
        );
        // Every face once per slab: 100 ids + 2 words per layer ≤ 256 words.
        assert_eq!(
            row_slabs(1024, 8, &[0; 20], 100).unwrap(),
            [0..8, 8..16, 16..20]
        );
        assert_eq!(row_slabs(1024, 8, &[0; 4], 250).unwrap(), [0..3, 3..4]);
        // Per layer lists of 100, 10, 10, 100, 200, 60 ids: 228 words,
        // then 202 (adding 62 would make 264).
        assert_eq!(
            row_slabs(1024, 1, &[100, 10, 10, 100, 200, 60], 0).unwrap(),
            [0..4, 4..5, 5..6]
        );
        for (ny, ids) in [(65, [0]), (1, [300])] {
            assert!(matches!(
                row_slabs(1024, ny, &ids, 0),
                Err(Error::Limit { allowed: 1024, .. })
            ));
        }
        assert!(row_slabs(1024, 1, &[], 0).unwrap().is_empty());
    }

    #[test]
    fn culling_lists_the_faces_meeting_each_layer() {
        // Layers k = 0..4 at z = 2·(−1 + k) + 1 = −1, 1, 3, 5, 7.
        let bbox = VoxelBox {
            origin: [0, 0, -1],
            dims: [1, 1, 5],
        };
        let c = Culling::new(&[[1, 4], [-9, 1], [2, 3], [0, 0], [6, 6]], &bbox);
        assert_eq!(
            c.layers,
            [Some([1, 2]), Some([0, 1]), Some([2, 2]), None, None]
        );
        // The faces' union is [−9, 6]: layer 4 (z = 7) lies outside it.
        assert_eq!(c.misses, [false, false, false, false, true]);
        let counts = c.counts();
        assert_eq!(counts, [1, 2, 2, 0, 0]);
        assert_eq!(
            c.lists(&(0..5), &counts),
            [
                10,
                11,
                11,
                13,
                13,
                15,
                15,
                15,
                LAYER_MISSES,
                LAYER_MISSES,
                1,
                0,
                1,
                0,
                2
            ]
        );
        assert_eq!(c.lists(&(2..4), &counts), [4, 6, 6, 6, 0, 2]);
    }
}
