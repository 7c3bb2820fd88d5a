// Exact signed 64-bit integers from 32-bit operations, for GPUs without
// SHADER_INT64: a value is vec2<u32>(low word, high word), two's complement.
// Products i32 × i32 are exact (16-bit limbs); sums wrap mod 2^64 like i64.
// Mirror: hull_scan::cpu::i32x2 (function for function).

// Sign-extends a.
fn w_from_i32(a: i32) -> vec2<u32> {
    return vec2<u32>(bitcast<u32>(a), select(0u, 0xffffffffu, a < 0));
}

// a + b mod 2^64 (carry out of the low word).
fn w_add(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    let carry = select(0u, 1u, lo < a.x);
    return vec2<u32>(lo, a.y + b.y + carry);
}

// -a mod 2^64.
fn w_neg(a: vec2<u32>) -> vec2<u32> {
    return w_add(~a, vec2<u32>(1u, 0u));
}

// a - b mod 2^64.
fn w_sub(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return w_add(a, w_neg(b));
}

// a · b for unsigned 32-bit words, exact in 64 bits.
fn w_mul_u32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = p01 + p10;
    let mid_carry = select(0u, 0x10000u, mid < p01);
    let lo = p00 + (mid << 16u);
    let lo_carry = select(0u, 1u, lo < p00);
    return vec2<u32>(lo, p11 + (mid >> 16u) + mid_carry + lo_carry);
}

// a · b for signed words, exact (|a·b| ≤ 2^62).
fn w_mul(a: i32, b: i32) -> vec2<u32> {
    let ua = select(bitcast<u32>(a), 0u - bitcast<u32>(a), a < 0);
    let ub = select(bitcast<u32>(b), 0u - bitcast<u32>(b), b < 0);
    let p = w_mul_u32(ua, ub);
    return select(p, w_neg(p), (a < 0) != (b < 0));
}

// a < b, signed.
fn w_lt(a: vec2<u32>, b: vec2<u32>) -> bool {
    let ah = bitcast<i32>(a.y);
    let bh = bitcast<i32>(b.y);
    return ah < bh || (ah == bh && a.x < b.x);
}

// a = b.
fn w_eq(a: vec2<u32>, b: vec2<u32>) -> bool {
    return all(a == b);
}

// a ≤ b, signed.
fn w_le(a: vec2<u32>, b: vec2<u32>) -> bool {
    return !w_lt(b, a);
}
