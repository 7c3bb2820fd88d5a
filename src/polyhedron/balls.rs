//! Decomposition of a voxel set into maximal digital balls (seed 003
//! §4.5.4), the deterministic treatment of background components with
//! genus > 0 (non-simple and branched tunnels, concavities with tunnels).
//!
//! A digital ball `B(c, r²)` is the set of voxels whose centres lie within
//! Euclidean distance `r` of the centre of voxel `c` (Def. DK3): `r² = 0`
//! is one voxel, `1` adds its 6 face neighbours, `2` the 12 edge
//! neighbours, `3` the 8 corner neighbours, and so on through every sum of
//! three squares. A digital ball is digitally convex (Def. DCS): the convex
//! hull of its centres contains no other voxel centre, so every ball is a
//! leaf of the modification (recursion depth 1).
//!
//! The algorithm grows a ball from a start voxel while (a) the next radius adds voxels and (b) all of them
//! belong to the set; when it stops, the ball is moved by one voxel along
//! ±x, ±y, ±z and regrown; a move is taken when the ball found there
//! contains the current one and is larger (seed Fig. 4.26). The maximal
//! ball is then removed from the set and the next ball starts. The seed
//! allows any start voxel; ours is the remaining voxel deepest inside the
//! set (largest squared Euclidean distance to the complement, computed once
//! by an exact separable distance transform; ties in file order), so the
//! big balls come first. The result is deterministic and covers the set
//! exactly with disjoint balls.

/// One maximal digital ball of a decomposition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DigitalBall {
    /// Centre voxel (local indices of the decomposed box).
    pub centre: [usize; 3],
    /// Squared radius `r²` (in voxels²).
    pub r2: u32,
    /// The ball's voxels (local linear indices, x fastest), ascending.
    pub voxels: Vec<usize>,
}

/// Offsets `o` with `|o|² ≤ r_max²`, sorted by `|o|²` (then
/// lexicographically), with the distinct `|o|²` levels.
struct Offsets {
    offsets: Vec<([i64; 3], u32)>,
}

impl Offsets {
    fn new(r_max: i64) -> Offsets {
        let mut offsets = Vec::new();
        for z in -r_max..=r_max {
            for y in -r_max..=r_max {
                for x in -r_max..=r_max {
                    let r2 = x * x + y * y + z * z;
                    if r2 <= r_max * r_max {
                        offsets.push(([x, y, z], r2 as u32));
                    }
                }
            }
        }
        offsets.sort_unstable_by_key(|&(o, r2)| (r2, o));
        Offsets { offsets }
    }
}

/// The decomposition of the `true` voxels of a `dims` mask (x fastest) into
/// maximal digital balls, in order of construction.
pub fn maximal_balls(dims: [usize; 3], mask: &[bool]) -> Vec<DigitalBall> {
    let r_max = (dims.iter().copied().max().unwrap_or(0) as i64 + 1) / 2;
    let table = Offsets::new(r_max);
    let mut remaining = mask.to_vec();
    let depth = squared_distance_transform(dims, mask);
    let mut order: Vec<usize> = (0..mask.len()).filter(|&i| mask[i]).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(depth[i]), i));
    let mut balls = Vec::new();
    for start in order {
        if !remaining[start] {
            continue;
        }
        let mut c = [
            start % dims[0],
            start / dims[0] % dims[1],
            start / (dims[0] * dims[1]),
        ];
        let mut ball = grow(&table, dims, &remaining, c);
        'moves: loop {
            for axis in 0..3 {
                for step in [-1i64, 1] {
                    let Some(n) = shifted(dims, c, axis, step) else {
                        continue;
                    };
                    if !remaining[index(dims, n)] {
                        continue;
                    }
                    let candidate = grow(&table, dims, &remaining, n);
                    if candidate.len() > ball.len() && contains_all(&candidate, &ball) {
                        (c, ball) = (n, candidate);
                        continue 'moves;
                    }
                }
            }
            break;
        }
        for &v in &ball {
            remaining[v] = false;
        }
        let r2 = radius2(&table, ball.len());
        ball.sort_unstable();
        balls.push(DigitalBall {
            centre: c,
            r2,
            voxels: ball,
        });
    }
    balls
}

/// Squared Euclidean distance (voxels²) from every voxel to the nearest
/// `false` voxel or the box outside, exact in integers (separable lower
/// envelope of parabolas, Felzenszwalb–Huttenlocher), one pass per axis.
fn squared_distance_transform(dims: [usize; 3], mask: &[bool]) -> Vec<i64> {
    let far = 3 * (dims.iter().copied().max().unwrap_or(0) as i64 + 2).pow(2);
    let mut d: Vec<i64> = mask.iter().map(|&m| if m { far } else { 0 }).collect();
    let strides = [1, dims[0], dims[0] * dims[1]];
    for axis in 0..3 {
        let n = dims[axis];
        let s = strides[axis];
        let mut line = vec![0i64; n + 2];
        let mut out = vec![0i64; n + 2];
        let starts: Vec<usize> = (0..mask.len())
            .filter(|&i| [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])][axis] == 0)
            .collect();
        for start in starts {
            // The line padded with one outside sample at each end.
            line[0] = 0;
            line[n + 1] = 0;
            for k in 0..n {
                line[k + 1] = d[start + k * s];
            }
            envelope(&line, &mut out);
            for k in 0..n {
                d[start + k * s] = out[k + 1];
            }
        }
    }
    d
}

/// 1-D squared distance transform of the sampled function `f` (lower
/// envelope of the parabolas `f(q) + (p − q)²`), exact in integers.
fn envelope(f: &[i64], out: &mut [i64]) {
    let n = f.len();
    let mut v = vec![0usize; n];
    // Boundaries between parabolas as fractions num/den (den > 0).
    let mut z: Vec<(i64, i64)> = vec![(0, 1); n + 1];
    let inter = |q: usize, p: usize| -> (i64, i64) {
        let (q, p) = (q as i64, p as i64);
        (f[q as usize] + q * q - f[p as usize] - p * p, 2 * (q - p))
    };
    let less_eq =
        |a: (i64, i64), b: (i64, i64)| a.0 as i128 * b.1 as i128 <= b.0 as i128 * a.1 as i128;
    let mut k = 0usize;
    v[0] = 0;
    z[0] = (i64::MIN / 4, 1);
    z[1] = (i64::MAX / 4, 1);
    for q in 1..n {
        let mut s = inter(q, v[k]);
        while less_eq(s, z[k]) {
            k -= 1;
            s = inter(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = (i64::MAX / 4, 1);
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate().take(n) {
        while less_eq(z[k + 1], (q as i64, 1)) {
            k += 1;
        }
        let dq = q as i64 - v[k] as i64;
        *o = dq * dq + f[v[k]];
    }
}

fn index(dims: [usize; 3], v: [usize; 3]) -> usize {
    v[0] + dims[0] * (v[1] + dims[1] * v[2])
}

fn shifted(dims: [usize; 3], c: [usize; 3], axis: usize, step: i64) -> Option<[usize; 3]> {
    let mut n = c;
    let moved = c[axis] as i64 + step;
    if moved < 0 || moved >= dims[axis] as i64 {
        return None;
    }
    n[axis] = moved as usize;
    Some(n)
}

/// The largest ball about `c` whose voxels all remain, as local indices in
/// table order (grown level by level: a level is taken only when every one
/// of its voxels remains).
fn grow(table: &Offsets, dims: [usize; 3], remaining: &[bool], c: [usize; 3]) -> Vec<usize> {
    let mut ball = Vec::new();
    let mut k = 0;
    let offsets = &table.offsets;
    while k < offsets.len() {
        let level = offsets[k].1;
        let end = offsets[k..]
            .iter()
            .position(|&(_, r2)| r2 != level)
            .map_or(offsets.len(), |p| k + p);
        let mut level_voxels = Vec::with_capacity(end - k);
        for &(o, _) in &offsets[k..end] {
            let p: [i64; 3] = std::array::from_fn(|a| c[a] as i64 + o[a]);
            if (0..3).any(|a| p[a] < 0 || p[a] >= dims[a] as i64) {
                return ball;
            }
            let i = index(dims, p.map(|x| x as usize));
            if !remaining[i] {
                return ball;
            }
            level_voxels.push(i);
        }
        ball.extend(level_voxels);
        k = end;
    }
    ball
}

/// Whether `big` (any order) contains every voxel of `small`.
fn contains_all(big: &[usize], small: &[usize]) -> bool {
    let mut sorted = big.to_vec();
    sorted.sort_unstable();
    small.iter().all(|v| sorted.binary_search(v).is_ok())
}

/// `r²` of the ball with `n` voxels (the level of its last offset).
fn radius2(table: &Offsets, n: usize) -> u32 {
    n.checked_sub(1).map_or(0, |last| table.offsets[last].1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_solid_box_starts_with_its_largest_ball() {
        let dims = [9, 9, 9];
        let mask = vec![true; 729];
        let balls = maximal_balls(dims, &mask);
        // The first ball is centred (deepest voxel) and reaches r² = 24,
        // the largest level whose offsets all stay within ±4.
        assert_eq!(balls[0].centre, [4, 4, 4]);
        assert_eq!(balls[0].r2, 24);
        assert_eq!(balls[0].voxels.len(), 485);
        let total: usize = balls.iter().map(|b| b.voxels.len()).sum();
        assert_eq!(total, 729);
        let mut all: Vec<usize> = balls.iter().flat_map(|b| b.voxels.clone()).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 729, "balls overlap");
    }

    #[test]
    fn distance_transform_is_exact() {
        let dims = [7, 5, 3];
        let mask: Vec<bool> = (0..105).map(|i| i != 17 && i != 60).collect();
        let d = squared_distance_transform(dims, &mask);
        let at = |i: usize| [i % 7, i / 7 % 5, i / 35].map(|c| c as i64);
        for i in 0..105 {
            let p = at(i);
            let mut best = i64::MAX;
            // Nearest false voxel or the outside (one step past the box).
            for j in (0..105).filter(|&j| !mask[j]) {
                let q = at(j);
                best = best.min((0..3).map(|a| (p[a] - q[a]).pow(2)).sum());
            }
            for (a, n) in [7i64, 5, 3].into_iter().enumerate() {
                best = best.min((p[a] + 1).pow(2)).min((n - p[a]).pow(2));
            }
            assert_eq!(d[i], if mask[i] { best } else { 0 }, "voxel {i}");
        }
    }

    #[test]
    fn a_thin_line_is_single_voxels() {
        let dims = [5, 1, 1];
        let balls = maximal_balls(dims, &[true; 5]);
        assert_eq!(balls.len(), 5);
        assert!(balls.iter().all(|b| b.r2 == 0 && b.voxels.len() == 1));
    }
}
