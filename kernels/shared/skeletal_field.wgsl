// Shared by implicit_field, particle_update and network_update: the
// skeletal implicit field F(x) = Σ wᵢ eᵢ(dᵢ(x)²) (or max), its gradient and
// its time derivative at a fixed point, over the rows of
// implicit::field (bindings 1–3; each kernel declares its own `Params` at
// binding 0). Culling by a uniform grid of ascending primitive lists.
// Mirror: implicit::field::cpu::{influence, skeletal_field}.

struct FieldParams {
    grid_origin: vec3<f32>,
    inv_cell: f32,
    grid_dims: vec3<u32>,
    n_prims: u32,
    iso: f32,
    blend_max: u32,
    piece_base: u32,
    cell_base: u32,
}

@group(0) @binding(1) var<uniform> field: FieldParams;
// Per primitive 2 rows (p0, p1, w, 1/R²), (ṗ0, ṗ1, ẇ, 0); from piece_base
// 4 rows per piece (a, 1/|b − a|²), (b, 0), (ȧ, 0), (ḃ, 0).
@group(0) @binding(2) var<storage, read> skeleton: array<vec4<f32>>;
// [kind × n | piece end × n | cell starts (#cells + 1, absolute) | ids].
@group(0) @binding(3) var<storage, read> table: array<u32>;

struct FieldSample {
    grad: vec3<f32>,
    value: f32,  // F − I
    rate: f32,   // ∂F/∂t at fixed x
}

// (e, de/ds, de/dp0, de/dp1) of influence `kind` at squared distance s.
fn influence(kind: u32, s: f32, p: vec4<f32>) -> vec4<f32> {
    let p0 = p.x;
    let p1 = p.y;
    let inv_r2 = p.w;
    if kind == 0u {
        let ex = exp(-p0 * s);
        let e = p1 * ex;
        return vec4<f32>(e, -p0 * e, -s * e, ex);
    }
    let t = s * inv_r2;
    if kind == 1u {
        if t >= 1.0 {
            return vec4<f32>(0.0);
        }
        let c = 1.0 + t * (-22.0 / 9.0 + t * (17.0 / 9.0 - 4.0 / 9.0 * t));
        let dc = -22.0 / 9.0 + t * (34.0 / 9.0 - 12.0 / 9.0 * t);
        return vec4<f32>(p1 * c, p1 * dc * inv_r2, p1 * dc * (-2.0 * t / p0), c);
    }
    if t <= 1.0 / 9.0 {
        let g = 1.0 - 3.0 * t;
        return vec4<f32>(p1 * g, -3.0 * p1 * inv_r2, 6.0 * p1 * t / p0, g);
    }
    if t < 1.0 {
        let d = sqrt(s);
        let g = 1.0 - d / p0;
        return vec4<f32>(1.5 * p1 * g * g, -1.5 * p1 * g / (p0 * d), 3.0 * p1 * g * d * inv_r2, 1.5 * g * g);
    }
    return vec4<f32>(0.0);
}

fn skeletal_field(x: vec3<f32>) -> FieldSample {
    var out = FieldSample(vec3<f32>(0.0), 0.0, 0.0);
    var total = 0.0;
    let c = floor((x - field.grid_origin) * field.inv_cell);
    let dims = field.grid_dims;
    if all(c >= vec3<f32>(0.0)) && all(c < vec3<f32>(dims)) {
        let cell = u32(c.x) + dims.x * (u32(c.y) + dims.y * u32(c.z));
        let at = field.cell_base + cell;
        for (var k = table[at]; k < table[at + 1u]; k++) {
            let i = table[k];
            let kind = table[i];
            let end = table[field.n_prims + i];
            var start = 0u;
            if i > 0u {
                start = table[field.n_prims + i - 1u];
            }
            let p = skeleton[2u * i];
            let dp = skeleton[2u * i + 1u];
            var best_s = 3.40282347e38;
            var best_d = vec3<f32>(0.0);
            var best_v = vec3<f32>(0.0);
            for (var j = start; j < end; j++) {
                let r = field.piece_base + 4u * j;
                let a = skeleton[r];
                let b = skeleton[r + 1u];
                let va = skeleton[r + 2u].xyz;
                let vb = skeleton[r + 3u].xyz;
                let ab = b.xyz - a.xyz;
                let ax = x - a.xyz;
                let u = clamp(dot(ax, ab) * a.w, 0.0, 1.0);
                let d = ax - u * ab;
                let s = dot(d, d);
                if s < best_s {
                    best_s = s;
                    best_d = d;
                    best_v = va + u * (vb - va);
                }
            }
            let e = influence(kind, best_s, p);
            let w = p.z;
            let f = w * e.x;
            let g = 2.0 * w * e.y;
            let grad = g * best_d;
            let rate = w * (-2.0 * e.y * dot(best_d, best_v) + e.z * dp.x + e.w * dp.y) + dp.z * e.x;
            if field.blend_max == 1u {
                if f > total {
                    total = f;
                    out.grad = grad;
                    out.rate = rate;
                }
            } else {
                total += f;
                out.grad += grad;
                out.rate += rate;
            }
        }
    }
    out.value = total - field.iso;
    return out;
}
