//! The step mirrors' wide gather on x86-64: 8 nodes side by side with
//! AVX2, 16 with AVX-512, one lane of a register each.
//!
//! Lane t sits in 128-bit part t / 4 at position t % 4. The neighbour rows
//! `[x, y, z, w]` of lanes t, t + 4, … are loaded into the parts of one
//! register, so the 4 × 4 transposes of the portable gather
//! ([`super::gather_group`]) run on every part at once and each arithmetic
//! instruction serves 8 or 16 springs. The free nodes' CSR rows are read
//! from [`LaneRows`], a copy interleaved by group (one load gives the
//! entries of all lanes, and the material parameters come from a register
//! table by permute), and the rest of each row from the CSR itself.
//!
//! Every lane performs exactly the float operations of one kernel
//! invocation in its CSR order: IEEE add, multiply, divide and square root,
//! nothing contracted to FMA, the operand order of `max` and the masks of
//! the portable gather. The results are its bits, and those of the plain
//! per-node loop (`tests/tissue.rs`).
//!
//! The code runs inside pulp's `vectorize` (run-time detection, safe
//! intrinsics). Everything called there that uses an intrinsic is an
//! `#[inline(always)]` function, never a closure, so that it is compiled
//! with the features.

use std::arch::x86_64::{__m256, __m256i, __m512, __m512i, __mmask16};

use pulp::NullaryFnOnce;
use pulp::x86::{V3, V4};

use super::SpringCsr;

/// The first `n_free` CSR rows in groups of `L` consecutive nodes (whole
/// groups only), interleaved for the wide gather: group g (nodes
/// `gL..gL + L`) holds, for each k below its shortest row's length, the k-th
/// entries of its L rows side by side. What is left of each row is read
/// from the CSR.
#[derive(Debug, Clone)]
pub(super) struct LaneRows<const L: usize> {
    /// Per group: its first step in `steps`, and its shortest row's length.
    groups: Vec<(usize, usize)>,
    steps: Vec<[u32; L]>,
}

impl<const L: usize> LaneRows<L> {
    pub(super) fn new(csr: &SpringCsr, n_free: usize) -> Self {
        let mut groups = Vec::with_capacity(n_free / L);
        let mut steps = Vec::new();
        for g in 0..n_free / L {
            let o = &csr.offsets[g * L..=g * L + L];
            let k_min = (0..L).map(|t| o[t + 1] - o[t]).min().unwrap_or(0) as usize;
            groups.push((steps.len(), k_min));
            steps.extend(
                (0..k_min).map(|k| std::array::from_fn(|t| csr.entries[o[t] as usize + k])),
            );
        }
        LaneRows { groups, steps }
    }

    /// Whole groups: the first `groups() · L` free nodes.
    pub(super) fn groups(&self) -> usize {
        self.groups.len()
    }
}

/// One SIMD width: `L` f32 lanes and the operations of the kernel's loop,
/// each the IEEE operation the portable gather performs.
trait Wide<const L: usize>: Copy {
    /// L f32 lanes.
    type F: Copy;
    /// A lane mask.
    type Mask: Copy;
    /// One column of the material table, ready for [`Wide::lookup`].
    type Table: Copy;
    /// The material ids of one step's entries.
    type Ids: Copy;

    fn zero(self) -> Self::F;
    fn splat(self, x: f32) -> Self::F;
    fn add(self, a: Self::F, b: Self::F) -> Self::F;
    fn sub(self, a: Self::F, b: Self::F) -> Self::F;
    fn mul(self, a: Self::F, b: Self::F) -> Self::F;
    fn div(self, a: Self::F, b: Self::F) -> Self::F;
    fn sqrt(self, a: Self::F) -> Self::F;
    /// `maxps a, b`: b where either is NaN, as `Vec4::max(a, b)`.
    fn max(self, a: Self::F, b: Self::F) -> Self::F;
    /// Where `a > b` (ordered), as `Vec4::cmpgt`.
    fn gt(self, a: Self::F, b: Self::F) -> Self::Mask;
    /// Where |a| < b (ordered).
    fn abs_lt(self, a: Self::F, b: Self::F) -> Self::Mask;
    /// `a` where `mask`, else `b`.
    fn select(self, mask: Self::Mask, a: Self::F, b: Self::F) -> Self::F;
    /// Rows `src[at(t)]` in lane order: register q holds the rows of lanes
    /// q, q + 4, … in its 128-bit parts.
    fn load(self, src: &[[f32; 4]], at: impl Fn(usize) -> usize) -> [Self::F; 4];
    /// The 4 × 4 transpose within every 128-bit part: from [`Wide::load`]'s
    /// order to component c (x, y, z, w) of every lane in register c, and
    /// back.
    fn transpose(self, r: [Self::F; 4]) -> [Self::F; 4];
    /// Writes [`Wide::load`]'s order back: lane t's row to `dst[t]`.
    fn store(self, r: [Self::F; 4], dst: &mut [[f32; 4]]);
    /// Component c of row `src[at(t)]` in lane t, for c = x, y, z, w.
    #[inline(always)]
    fn rows(self, src: &[[f32; 4]], at: impl Fn(usize) -> usize) -> [Self::F; 4] {
        self.transpose(self.load(src, at))
    }
    fn table(self, column: [f32; 16]) -> Self::Table;
    /// The material ids (entry bits 28–31) of one step.
    fn ids(self, step: [u32; L]) -> Self::Ids;
    /// Each lane's material's value in `table`.
    fn lookup(self, table: Self::Table, ids: Self::Ids) -> Self::F;
    /// Runs `f` compiled with this width's CPU features.
    fn vectorize<R>(self, f: impl NullaryFnOnce<Output = R>) -> R;
}

impl Wide<8> for V3 {
    type F = __m256;
    type Mask = __m256;
    type Table = [__m256; 2];
    type Ids = __m256i;

    #[inline(always)]
    fn zero(self) -> __m256 {
        self.avx._mm256_setzero_ps()
    }
    #[inline(always)]
    fn splat(self, x: f32) -> __m256 {
        self.avx._mm256_set1_ps(x)
    }
    #[inline(always)]
    fn add(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_add_ps(a, b)
    }
    #[inline(always)]
    fn sub(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_sub_ps(a, b)
    }
    #[inline(always)]
    fn mul(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_mul_ps(a, b)
    }
    #[inline(always)]
    fn div(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_div_ps(a, b)
    }
    #[inline(always)]
    fn sqrt(self, a: __m256) -> __m256 {
        self.avx._mm256_sqrt_ps(a)
    }
    #[inline(always)]
    fn max(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_max_ps(a, b)
    }
    #[inline(always)]
    fn gt(self, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_cmp_ps::<0x1e>(a, b)
    }
    #[inline(always)]
    fn abs_lt(self, a: __m256, b: __m256) -> __m256 {
        let abs = self.avx._mm256_and_ps(a, pulp::cast([0x7fff_ffff_u32; 8]));
        self.avx._mm256_cmp_ps::<0x11>(abs, b)
    }
    #[inline(always)]
    fn select(self, mask: __m256, a: __m256, b: __m256) -> __m256 {
        self.avx._mm256_blendv_ps(b, a, mask)
    }
    #[inline(always)]
    fn load(self, src: &[[f32; 4]], at: impl Fn(usize) -> usize) -> [__m256; 4] {
        [
            pulp::cast([src[at(0)], src[at(4)]]),
            pulp::cast([src[at(1)], src[at(5)]]),
            pulp::cast([src[at(2)], src[at(6)]]),
            pulp::cast([src[at(3)], src[at(7)]]),
        ]
    }
    #[inline(always)]
    fn store(self, r: [__m256; 4], dst: &mut [[f32; 4]]) {
        let dst = &mut dst[..8];
        for (q, r) in r.into_iter().enumerate() {
            let [lo, hi]: [[f32; 4]; 2] = pulp::cast(r);
            (dst[q], dst[q + 4]) = (lo, hi);
        }
    }
    #[inline(always)]
    fn transpose(self, [a, b, c, d]: [__m256; 4]) -> [__m256; 4] {
        let avx = self.avx;
        let (t0, t1) = (avx._mm256_unpacklo_ps(a, b), avx._mm256_unpacklo_ps(c, d));
        let (t2, t3) = (avx._mm256_unpackhi_ps(a, b), avx._mm256_unpackhi_ps(c, d));
        [
            avx._mm256_shuffle_ps::<0x44>(t0, t1),
            avx._mm256_shuffle_ps::<0xee>(t0, t1),
            avx._mm256_shuffle_ps::<0x44>(t2, t3),
            avx._mm256_shuffle_ps::<0xee>(t2, t3),
        ]
    }
    #[inline(always)]
    fn table(self, column: [f32; 16]) -> [__m256; 2] {
        pulp::cast(column)
    }
    #[inline(always)]
    fn ids(self, step: [u32; 8]) -> __m256i {
        self.avx2._mm256_srli_epi32::<28>(pulp::cast(step))
    }
    #[inline(always)]
    fn lookup(self, table: [__m256; 2], ids: __m256i) -> __m256 {
        // Ids 0–7 from the first half, 8–15 (bit 3, moved to the sign)
        // from the second.
        let low = self.avx2._mm256_permutevar8x32_ps(table[0], ids);
        let high = self.avx2._mm256_permutevar8x32_ps(table[1], ids);
        let upper = self
            .avx
            ._mm256_castsi256_ps(self.avx2._mm256_slli_epi32::<28>(ids));
        self.avx._mm256_blendv_ps(low, high, upper)
    }
    #[inline(always)]
    fn vectorize<R>(self, f: impl NullaryFnOnce<Output = R>) -> R {
        V3::vectorize(self, f)
    }
}

impl Wide<16> for V4 {
    type F = __m512;
    type Mask = __mmask16;
    type Table = __m512;
    type Ids = __m512i;

    #[inline(always)]
    fn zero(self) -> __m512 {
        self.avx512f._mm512_setzero_ps()
    }
    #[inline(always)]
    fn splat(self, x: f32) -> __m512 {
        self.avx512f._mm512_set1_ps(x)
    }
    #[inline(always)]
    fn add(self, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_add_ps(a, b)
    }
    #[inline(always)]
    fn sub(self, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_sub_ps(a, b)
    }
    #[inline(always)]
    fn mul(self, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_mul_ps(a, b)
    }
    #[inline(always)]
    fn div(self, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_div_ps(a, b)
    }
    #[inline(always)]
    fn sqrt(self, a: __m512) -> __m512 {
        self.avx512f._mm512_sqrt_ps(a)
    }
    #[inline(always)]
    fn max(self, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_max_ps(a, b)
    }
    #[inline(always)]
    fn gt(self, a: __m512, b: __m512) -> __mmask16 {
        self.avx512f._mm512_cmp_ps_mask::<0x1e>(a, b)
    }
    #[inline(always)]
    fn abs_lt(self, a: __m512, b: __m512) -> __mmask16 {
        let abs = self
            .avx512dq
            ._mm512_and_ps(a, pulp::cast([0x7fff_ffff_u32; 16]));
        self.avx512f._mm512_cmp_ps_mask::<0x11>(abs, b)
    }
    #[inline(always)]
    fn select(self, mask: __mmask16, a: __m512, b: __m512) -> __m512 {
        self.avx512f._mm512_mask_blend_ps(mask, b, a)
    }
    #[inline(always)]
    fn load(self, src: &[[f32; 4]], at: impl Fn(usize) -> usize) -> [__m512; 4] {
        [
            pulp::cast([src[at(0)], src[at(4)], src[at(8)], src[at(12)]]),
            pulp::cast([src[at(1)], src[at(5)], src[at(9)], src[at(13)]]),
            pulp::cast([src[at(2)], src[at(6)], src[at(10)], src[at(14)]]),
            pulp::cast([src[at(3)], src[at(7)], src[at(11)], src[at(15)]]),
        ]
    }
    #[inline(always)]
    fn store(self, r: [__m512; 4], dst: &mut [[f32; 4]]) {
        let dst = &mut dst[..16];
        for (q, r) in r.into_iter().enumerate() {
            let [a, b, c, d]: [[f32; 4]; 4] = pulp::cast(r);
            (dst[q], dst[q + 4], dst[q + 8], dst[q + 12]) = (a, b, c, d);
        }
    }
    #[inline(always)]
    fn transpose(self, [a, b, c, d]: [__m512; 4]) -> [__m512; 4] {
        let f = self.avx512f;
        let (t0, t1) = (f._mm512_unpacklo_ps(a, b), f._mm512_unpacklo_ps(c, d));
        let (t2, t3) = (f._mm512_unpackhi_ps(a, b), f._mm512_unpackhi_ps(c, d));
        [
            f._mm512_shuffle_ps::<0x44>(t0, t1),
            f._mm512_shuffle_ps::<0xee>(t0, t1),
            f._mm512_shuffle_ps::<0x44>(t2, t3),
            f._mm512_shuffle_ps::<0xee>(t2, t3),
        ]
    }
    #[inline(always)]
    fn table(self, column: [f32; 16]) -> __m512 {
        pulp::cast(column)
    }
    #[inline(always)]
    fn ids(self, step: [u32; 16]) -> __m512i {
        self.avx512f._mm512_srli_epi32::<28>(pulp::cast(step))
    }
    #[inline(always)]
    fn lookup(self, table: __m512, ids: __m512i) -> __m512 {
        self.avx512f._mm512_permutexvar_ps(ids, table)
    }
    #[inline(always)]
    fn vectorize<R>(self, f: impl NullaryFnOnce<Output = R>) -> R {
        V4::vectorize(self, f)
    }
}

/// A group's own nodes (x_rest,i and u_i by component), the arrays its
/// neighbours are read from, and η.
struct Group<'a, F> {
    rest: &'a [[f32; 4]],
    pos_in: &'a [[f32; 4]],
    x0: [F; 3],
    u: [F; 3],
    eta: F,
}

/// Running sums of a group: g by component, the six block sums and the
/// isotropic part of the block diagonal.
struct Acc<F> {
    g: [F; 3],
    blocks: [F; 6],
    iso: F,
}

/// Adds one spring per lane: lane t's neighbour `j(t)` with material
/// `[c1, c2 − c1, knee, c_max]` (an all-zero material and the lane's own
/// node past its row's end), the operations of the portable gather's loop.
#[inline(always)]
fn spring<W: Wide<L>, const L: usize, const BLOCKS: bool>(
    w: W,
    grp: &Group<'_, W::F>,
    acc: &mut Acc<W::F>,
    j: impl Fn(usize) -> usize + Copy,
    [c1, dc, knee, c_max]: [W::F; 4],
) {
    let [rjx, rjy, rjz, _] = w.rows(grp.rest, j);
    let [ujx, ujy, ujz, _] = w.rows(grp.pos_in, j);
    let [x0x, x0y, x0z] = grp.x0;
    let [ux, uy, uz] = grp.u;
    let (dx, dy, dz) = (w.sub(x0x, rjx), w.sub(x0y, rjy), w.sub(x0z, rjz));
    let rx = w.add(dx, w.sub(ux, ujx));
    let ry = w.add(dy, w.sub(uy, ujy));
    let rz = w.add(dz, w.sub(uz, ujz));
    let l = norm(w, dx, dy, dz);
    let len = norm(w, rx, ry, rz);
    let ext = w.sub(len, l);
    let bent = w.max(w.sub(ext, w.mul(knee, l)), w.zero());
    let f = w.add(w.mul(c1, ext), w.mul(dc, bent));
    let s = w.div(f, len);
    let on = w.gt(len, w.zero());
    let zero = w.zero();
    acc.g[0] = w.add(acc.g[0], w.select(on, w.mul(s, rx), zero));
    acc.g[1] = w.add(acc.g[1], w.select(on, w.mul(s, ry), zero));
    acc.g[2] = w.add(acc.g[2], w.select(on, w.mul(s, rz), zero));
    if BLOCKS {
        let across = w.max(w.mul(grp.eta, c_max), s);
        let q = w.select(on, w.div(w.sub(c_max, across), w.mul(len, len)), zero);
        let (qx, qy, qz) = (w.mul(q, rx), w.mul(q, ry), w.mul(q, rz));
        let terms = [
            w.mul(qx, rx),
            w.mul(qy, ry),
            w.mul(qz, rz),
            w.mul(qx, ry),
            w.mul(qx, rz),
            w.mul(qy, rz),
        ];
        for (b, t) in acc.blocks.iter_mut().zip(terms) {
            *b = w.add(*b, t);
        }
        acc.iso = w.add(acc.iso, w.select(on, across, c_max));
    }
}

/// √((x² + y²) + z²).
#[inline(always)]
fn norm<W: Wide<L>, const L: usize>(w: W, x: W::F, y: W::F, z: W::F) -> W::F {
    w.sqrt(w.add(w.add(w.mul(x, x), w.mul(y, y)), w.mul(z, z)))
}

/// The group's sums after its springs: g by component and the block
/// `[b00, b11, b22, b01, b02, b12]` (isotropic part added; zeros without
/// `BLOCKS`), and its own `u` and `w` by component (see
/// [`super::gather_group`]).
struct Gathered<F> {
    g: [F; 3],
    blocks: [F; 6],
    u: [F; 3],
    w: F,
}

/// Gathers the L nodes of group `g`.
#[inline(always)]
fn gather_group<W: Wide<L>, const L: usize, const BLOCKS: bool>(
    w: W,
    g: usize,
    rows: &LaneRows<L>,
    tables: [W::Table; 4],
    b: &Bindings<'_>,
) -> Gathered<W::F> {
    let n = b.rest.len().min(b.pos_in.len());
    let (rest, pos_in, csr) = (&b.rest[..n], &b.pos_in[..n], b.csr);
    let own = |t: usize| g * L + t;
    let [x0x, x0y, x0z, _] = w.rows(rest, own);
    let [ux, uy, uz, uw] = w.rows(pos_in, own);
    let grp = Group {
        rest,
        pos_in,
        x0: [x0x, x0y, x0z],
        u: [ux, uy, uz],
        eta: w.splat(b.isotropy),
    };
    let mut acc = Acc {
        g: [w.zero(); 3],
        blocks: [w.zero(); 6],
        iso: w.zero(),
    };
    // While every lane has a spring left: interleaved steps, materials by
    // permute.
    let (first, k_min) = rows.groups[g];
    for step in &rows.steps[first..first + k_min] {
        let j = |t: usize| SpringCsr::unpack(step[t]).0;
        let ids = w.ids(*step);
        let m = [
            w.lookup(tables[0], ids),
            w.lookup(tables[1], ids),
            w.lookup(tables[2], ids),
            w.lookup(tables[3], ids),
        ];
        spring::<W, L, BLOCKS>(w, &grp, &mut acc, j, m);
    }
    // Then lane by lane from the CSR.
    let offsets = &csr.offsets[g * L..=g * L + L];
    let k_end = (0..L)
        .map(|t| offsets[t + 1] - offsets[t])
        .max()
        .unwrap_or(0) as usize;
    for k in k_min..k_end {
        let mut j: [usize; L] = std::array::from_fn(own);
        let mut m = [[0.0f32; 4]; L];
        for t in 0..L {
            let at = offsets[t] as usize + k;
            if at < offsets[t + 1] as usize {
                let (jt, mt) = SpringCsr::unpack(csr.entries[at]);
                (j[t], m[t]) = (jt, b.materials[mt]);
            }
        }
        let m = w.rows(&m, |t| t);
        spring::<W, L, BLOCKS>(w, &grp, &mut acc, |t| j[t], m);
    }
    if BLOCKS {
        for b in &mut acc.blocks[..3] {
            *b = w.add(*b, acc.iso);
        }
    }
    Gathered {
        g: acc.g,
        blocks: acc.blocks,
        u: grp.u,
        w: uw,
    }
}

/// `|x| < VELOCITY_FLUSH ? 0 : x`, as [`super::flush`].
#[inline(always)]
fn flush<W: Wide<L>, const L: usize>(w: W, x: W::F) -> W::F {
    w.select(w.abs_lt(x, w.splat(super::VELOCITY_FLUSH)), w.zero(), x)
}

/// [`super::block_solve`] by lane: B⁻¹ d, 0 where tr B ≤ 0.
#[inline(always)]
fn block_solve<W: Wide<L>, const L: usize>(w: W, b: [W::F; 6], d: [W::F; 3]) -> [W::F; 3] {
    let tr = w.add(w.add(b[0], b[1]), b[2]);
    let [a0, a1, a2, o0, o1, o2] = [
        w.div(b[0], tr),
        w.div(b[1], tr),
        w.div(b[2], tr),
        w.div(b[3], tr),
        w.div(b[4], tr),
        w.div(b[5], tr),
    ];
    let c00 = w.sub(w.mul(a1, a2), w.mul(o2, o2));
    let c01 = w.sub(w.mul(o1, o2), w.mul(o0, a2));
    let c02 = w.sub(w.mul(o0, o2), w.mul(o1, a1));
    let c11 = w.sub(w.mul(a0, a2), w.mul(o1, o1));
    let c12 = w.sub(w.mul(o0, o1), w.mul(a0, o2));
    let c22 = w.sub(w.mul(a0, a1), w.mul(o0, o0));
    let det = dot(w, [a0, o0, o1], [c00, c01, c02]);
    let wt = w.mul(det, tr);
    let x = [
        w.div(dot(w, [c00, c01, c02], d), wt),
        w.div(dot(w, [c01, c11, c12], d), wt),
        w.div(dot(w, [c02, c12, c22], d), wt),
    ];
    let solvable = w.gt(tr, w.zero());
    [
        w.select(solvable, x[0], w.zero()),
        w.select(solvable, x[1], w.zero()),
        w.select(solvable, x[2], w.zero()),
    ]
}

/// (p₀q₀ + p₁q₁) + p₂q₂.
#[inline(always)]
fn dot<W: Wide<L>, const L: usize>(w: W, p: [W::F; 3], q: [W::F; 3]) -> W::F {
    w.add(
        w.add(w.mul(p[0], q[0]), w.mul(p[1], q[1])),
        w.mul(p[2], q[2]),
    )
}

/// The gather's bindings and the update's outputs: the rayon task's nodes
/// `first..first + pos_out.len()`.
pub(super) struct Bindings<'a> {
    pub csr: &'a SpringCsr,
    pub rest: &'a [[f32; 4]],
    pub pos_in: &'a [[f32; 4]],
    pub forces: &'a [[f32; 4]],
    pub use_forces: bool,
    pub materials: &'a [[f32; 4]; 16],
    pub isotropy: f32,
    pub update: super::Update,
}

/// One step of group `g` (its first node at `at` of `pos_out` and `vel`):
/// the gather, then [`super::Update`] by lane, written back row by row.
#[inline(always)]
fn step_group<W: Wide<L>, const L: usize, const BLOCKS: bool>(
    w: W,
    g: usize,
    rows: &LaneRows<L>,
    tables: [W::Table; 4],
    b: &Bindings<'_>,
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    let s = gather_group::<W, L, BLOCKS>(w, g, rows, tables, b);
    let f = if b.use_forces {
        let [fx, fy, fz, _] = w.rows(b.forces, |t| g * L + t);
        [fx, fy, fz]
    } else {
        [w.zero(); 3]
    };
    let [vx, vy, vz, _] = w.rows(vel, |t| t);
    let v = [vx, vy, vz];
    let (u2, v2) = match b.update {
        super::Update::Explicit { dt, gamma } => {
            // eq. 4.5: a = (f − γ v − g) · B/m;  eq. 4.7: v += Δt a; u += Δt v.
            let (dt, gamma) = (w.splat(dt), w.splat(gamma));
            let mut u2 = [w.zero(); 3];
            let mut v2 = [w.zero(); 3];
            for k in 0..3 {
                let a = w.mul(w.sub(w.sub(f[k], w.mul(gamma, v[k])), s.g[k]), s.w);
                v2[k] = flush(w, w.add(v[k], w.mul(dt, a)));
                u2[k] = w.add(s.u[k], w.mul(dt, v2[k]));
            }
            (u2, v2)
        }
        super::Update::Chebyshev { h, beta, gain } => {
            let d = [
                w.sub(f[0], s.g[0]),
                w.sub(f[1], s.g[1]),
                w.sub(f[2], s.g[2]),
            ];
            let r = block_solve(w, s.blocks, d);
            let (h, beta, gain) = (w.splat(h), w.splat(beta), w.splat(gain));
            let mut u2 = [w.zero(); 3];
            let mut v2 = [w.zero(); 3];
            for k in 0..3 {
                v2[k] = flush(w, w.add(w.mul(beta, v[k]), w.mul(gain, r[k])));
                u2[k] = w.add(s.u[k], w.mul(h, v2[k]));
            }
            (u2, v2)
        }
    };
    w.store(w.transpose([u2[0], u2[1], u2[2], s.w]), pos_out);
    w.store(w.transpose([v2[0], v2[1], v2[2], w.zero()]), vel);
}

/// Steps the groups `groups` of `rows` with width `w`: the rayon task's
/// outputs `pos_out` and `vel` start at group `groups.start`.
#[inline(always)]
fn run<W: Wide<L>, const L: usize, const BLOCKS: bool>(
    w: W,
    rows: &LaneRows<L>,
    groups: std::ops::Range<usize>,
    b: &Bindings<'_>,
    pos_out: &mut [[f32; 4]],
    vel: &mut [[f32; 4]],
) {
    struct Run<'a, W, const L: usize, const BLOCKS: bool> {
        w: W,
        rows: &'a LaneRows<L>,
        groups: std::ops::Range<usize>,
        b: &'a Bindings<'a>,
        pos_out: &'a mut [[f32; 4]],
        vel: &'a mut [[f32; 4]],
    }
    impl<W: Wide<L>, const L: usize, const BLOCKS: bool> NullaryFnOnce for Run<'_, W, L, BLOCKS> {
        type Output = ();
        #[inline(always)]
        fn call(self) {
            let Run {
                w,
                rows,
                groups,
                b,
                pos_out,
                vel,
            } = self;
            let m = b.materials;
            let columns: [[f32; 16]; 4] = [0, 1, 2, 3].map(|c| std::array::from_fn(|r| m[r][c]));
            let tables = [
                w.table(columns[0]),
                w.table(columns[1]),
                w.table(columns[2]),
                w.table(columns[3]),
            ];
            let outs = pos_out.chunks_exact_mut(L).zip(vel.chunks_exact_mut(L));
            for (g, (po, ve)) in groups.zip(outs) {
                step_group::<W, L, BLOCKS>(w, g, rows, tables, b, po, ve);
            }
        }
    }
    w.vectorize(Run::<_, L, BLOCKS> {
        w,
        rows,
        groups,
        b,
        pos_out,
        vel,
    });
}

/// The CSR arranged for the widest gather this CPU has (see
/// [`super::Lanes`]).
#[derive(Debug, Clone)]
pub(super) enum WideRows {
    /// AVX2: groups of 8.
    Eight(LaneRows<8>),
    /// AVX-512: groups of 16.
    Sixteen(LaneRows<16>),
}

impl WideRows {
    /// Nodes per group.
    pub(super) fn width(&self) -> usize {
        match self {
            WideRows::Eight(_) => 8,
            WideRows::Sixteen(_) => 16,
        }
    }

    /// Whole groups.
    pub(super) fn groups(&self) -> usize {
        match self {
            WideRows::Eight(r) => r.groups(),
            WideRows::Sixteen(r) => r.groups(),
        }
    }

    /// Steps the groups `groups` (see [`run`]); false where this CPU lacks
    /// the width's features (nothing written).
    pub(super) fn run<const BLOCKS: bool>(
        &self,
        groups: std::ops::Range<usize>,
        b: &Bindings<'_>,
        pos_out: &mut [[f32; 4]],
        vel: &mut [[f32; 4]],
    ) -> bool {
        match self {
            WideRows::Eight(rows) => V3::try_new()
                .map(|w| run::<V3, 8, BLOCKS>(w, rows, groups, b, pos_out, vel))
                .is_some(),
            WideRows::Sixteen(rows) => V4::try_new()
                .map(|w| run::<V4, 16, BLOCKS>(w, rows, groups, b, pos_out, vel))
                .is_some(),
        }
    }
}
