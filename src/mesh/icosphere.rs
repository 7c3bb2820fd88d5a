//! Icospheres: a regular icosahedron subdivided, its vertices on the sphere.

use glam::DVec3;

/// Unit icosphere with `level` subdivisions, outward winding: 10·4ⁿ + 2
/// vertices (f64, on the unit sphere) and 20·4ⁿ triangles. Each level
/// splits every edge at its midpoint pushed onto the sphere.
pub fn unit_icosphere(level: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .map(|a| DVec3::from_array(a).normalize())
    .to_vec();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push((p[a as usize] + p[b as usize]).normalize());
                (p.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(t.len() * 4);
        for [a, b, c] in t {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        t = next;
    }
    (p, t)
}

/// Largest depth below the unit sphere of a triangle of a unit icosphere
/// (`points`, `triangles` from [`unit_icosphere`]): 1 − the least distance
/// of a triangle's plane from the centre.
pub fn icosphere_sag(points: &[DVec3], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|v| points[v as usize]);
            1.0 - (b - a).cross(c - a).normalize().dot(a).abs()
        })
        .fold(0.0, f64::max)
}
