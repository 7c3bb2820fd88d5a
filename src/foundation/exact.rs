//! Exact integer geometry: points and vectors with `i64` coordinates,
//! products in `i128` where their range needs it. No epsilons: callers
//! bound their coordinates (each room states its `MAX_COORD`) so that every
//! expression here is exact. And the exact orientation signs of f64 points
//! ([`orient3d_sign`], [`orient2d_sign`]: Shewchuk's adaptive predicates)
//! that the float-mesh tests (self-intersection, point in mesh) decide by.

/// A point or vector in 3-D.
pub type P3 = [i64; 3];
/// A point or vector in 2-D.
pub type P2 = [i64; 2];

/// `a − b`.
pub fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a × b` in `i64` (for coordinates below 2³¹ in magnitude).
pub fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a × b` in `i128` (any `i64` coordinates below 2⁶² in magnitude).
pub fn cross_wide(a: P3, b: P3) -> [i128; 3] {
    let (a, b) = (a.map(i128::from), b.map(i128::from));
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a · b` in `i64`.
pub fn dot(a: P3, b: P3) -> i64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `det(a, b, c)` (rows) in `i128`: six times the signed volume of the
/// tetrahedron `0 a b c` (for coordinates up to about 2⁴¹).
pub fn det(a: P3, b: P3, c: P3) -> i128 {
    let (a, b, c) = (a.map(i128::from), b.map(i128::from), c.map(i128::from));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// Greatest common divisor, non-negative (`gcd(0, 0) = 0`).
pub fn gcd(mut a: i64, mut b: i64) -> i64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.abs()
}

/// `a − b` in 2-D, widened to `i128`.
pub fn sub2(a: P2, b: P2) -> [i128; 2] {
    [i128::from(a[0] - b[0]), i128::from(a[1] - b[1])]
}

/// The 2-D cross product `a × b` (> 0: `b` turns counter-clockwise from `a`).
pub fn cross2(a: [i128; 2], b: [i128; 2]) -> i128 {
    a[0] * b[1] - a[1] * b[0]
}

/// The 2-D dot product.
pub fn dot2(a: [i128; 2], b: [i128; 2]) -> i128 {
    a[0] * b[0] + a[1] * b[1]
}

/// Twice the signed area of triangle `a b c` (> 0 counter-clockwise).
pub fn orient2(a: P2, b: P2, c: P2) -> i128 {
    cross2(sub2(b, a), sub2(c, a))
}

/// Exact sign of the orientation of `d` against the plane of `abc` on f64
/// coordinates (Shewchuk's adaptive `orient3d`, crate `robust`): 1 when `d`
/// lies in front of `abc` (on the side of its right-hand normal), −1
/// behind, 0 on the plane.
pub fn orient3d_sign(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> i8 {
    let c3 = |v: [f64; 3]| robust::Coord3D {
        x: v[0],
        y: v[1],
        z: v[2],
    };
    // Shewchuk's value is positive when d lies below (behind) abc.
    let v = robust::orient3d(c3(a), c3(b), c3(c), c3(d));
    (v < 0.0) as i8 - (v > 0.0) as i8
}

/// Exact sign of the orientation of `abc` in the plane on f64 coordinates
/// (`orient2d`): 1 counter-clockwise, −1 clockwise, 0 collinear.
pub fn orient2d_sign(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let c2 = |v: [f64; 2]| robust::Coord { x: v[0], y: v[1] };
    let v = robust::orient2d(c2(a), c2(b), c2(c));
    (v > 0.0) as i8 - (v < 0.0) as i8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_are_exact_at_their_ranges() {
        let big = 1i64 << 40;
        assert_eq!(cross_wide([big, 0, 0], [0, big, 0]), [0, 0, 1i128 << 80]);
        assert_eq!(det([big, 0, 0], [0, big, 0], [0, 0, big]), 1i128 << 120);
        assert_eq!(det([1, 2, 3], [4, 5, 6], [7, 8, 10]), -3);
        assert_eq!(cross([1, 0, 0], [0, 1, 0]), [0, 0, 1]);
        assert_eq!(dot(sub([3, 4, 5], [1, 1, 1]), [1, 1, 1]), 9);
        assert_eq!(orient2([0, 0], [1, 0], [0, 1]), 1);
        assert_eq!(orient2([0, 0], [0, 1], [1, 0]), -1);
        assert_eq!(orient2([0, 0], [1, 1], [2, 2]), 0);
    }

    #[test]
    fn gcd_is_non_negative() {
        assert_eq!(gcd(12, -18), 6);
        assert_eq!(gcd(-12, 0), 12);
        assert_eq!(gcd(0, 0), 0);
        assert_eq!([4, -6, 10].iter().fold(0, |g, &c| gcd(g, c)), 2);
    }
}
