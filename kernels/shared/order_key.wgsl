// Shared: order-preserving u32 keys of f32 bit patterns (IEEE 754 §5.10
// totalOrder). key(a) < key(b) ⇔ a precedes b in totalOrder, so integer
// min/max of keys is an exact float min/max that does not depend on the
// reduction order: −0 < +0, ±inf at the ends, a NaN beyond them on the side
// of its sign bit. The host inverts keys with reduce::cpu::from_key.
// Mirror: reduce::cpu::order_key.
fn order_key(bits: u32) -> u32 {
    return select(bits | 0x80000000u, ~bits, (bits & 0x80000000u) != 0u);
}

// order_key, component-wise.
fn order_key4(bits: vec4<u32>) -> vec4<u32> {
    let neg = (bits & vec4<u32>(0x80000000u)) != vec4<u32>(0u);
    return select(bits | vec4<u32>(0x80000000u), ~bits, neg);
}
