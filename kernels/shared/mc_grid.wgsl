// Shared by mc_inside and mc_vertices: the samples of the padded
// marching-cubes grid, read from the volume's own type: `samples`
// (binding 1 of both kernels) holds the words of the inner layers from
// grid.z_first — one f32, two 16-bit or four 8-bit samples a word, the
// first in the low bits. Each kernel passes its `params.grid`. Padding and
// labels are applied here, not by a conversion pass on the host.
// Mirror: mc::grid::{grid_sample, inner_sample}.

struct SampleGrid {
    nx: u32,
    ny: u32,
    nz: u32,
    z_first: u32,  // first inner layer held by `samples`
    pad: u32,      // 1: closed border, one padding sample per side
    kind: u32,     // 0 f32, 1 i16, 2 u16, 3 i8, 4 u8 (mc::grid::SampleKind)
    labels: u32,   // 1: a sample is 1 where it equals `label`, else 0
    label: f32,    // NaN where no sample can equal the label
    outside: f32,  // the padding's outside value
    level: f32,
    unused0: u32,
    unused1: u32,
}

@group(0) @binding(1) var<storage, read> samples: array<u32>;

// Inner sample i (relative to layer z_first) decoded from its word,
// without branches: kind 0 is f32, kinds 1–2 two 16-bit samples a word,
// 3–4 four 8-bit ones; odd kinds are signed (sign-extended by shifting the
// sample to the top of the word and back).
fn inner_sample(g: SampleGrid, i: u32) -> f32 {
    let lg = select(select(2u, 1u, g.kind <= 2u), 0u, g.kind == 0u);
    let w = samples[i >> lg];
    let width = 32u >> lg;
    let top = (w >> ((i & ((1u << lg) - 1u)) * width)) << (32u - width);
    let signed = (g.kind & 1u) == 1u;
    let n = select(f32(top >> (32u - width)), f32(bitcast<i32>(top) >> (32u - width)), signed);
    let s = select(n, bitcast<f32>(w), g.kind == 0u);
    return select(s, select(0.0, 1.0, s == g.label), g.labels == 1u);
}

// Sample (x, y, z) of the padded grid. A padding sample next to one inner
// sample s (one coordinate outside) is 2·level − s capped at `outside`
// where s > level, else `outside`; padding edges and corners are `outside`.
fn grid_sample(g: SampleGrid, x: u32, y: u32, z: u32) -> f32 {
    let p = vec3<u32>(g.pad);
    let v = vec3<u32>(g.nx, g.ny, g.nz) - 2u * p;
    let c = vec3<u32>(x, y, z);
    // Below the padding the subtraction wraps past every inner index.
    let i = c - p;
    if all(i < v) {
        return inner_sample(g, i.x + v.x * (i.y + v.y * (i.z - g.z_first)));
    }
    return padding_sample(g, c, v);
}

// A padding sample: the inner sample next to it (coordinates clamped to
// the inner grid) mirrored, or `outside`.
fn padding_sample(g: SampleGrid, c: vec3<u32>, v: vec3<u32>) -> f32 {
    let p = vec3<u32>(g.pad);
    let below = c < p;
    let i = min(select(c - p, vec3<u32>(0u), below), v - vec3<u32>(1u));
    let outer = below | (c >= v + p);
    let n_pad = select(0u, 1u, outer.x) + select(0u, 1u, outer.y) + select(0u, 1u, outer.z);
    let s = inner_sample(g, i.x + v.x * (i.y + v.y * (i.z - g.z_first)));
    if n_pad == 1u && s > g.level {
        return min(2.0 * g.level - s, g.outside);
    }
    return g.outside;
}
