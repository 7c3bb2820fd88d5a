//! A linear bounding-volume hierarchy over a mesh's triangles, built on the
//! host from Morton codes and laid out for a stackless walk.
//!
//! Build (Lauterbach et al. 2009, "LBVH"): every triangle's centroid gets a
//! 30-bit Morton code in the centroids' bounding box; the triangles are
//! sorted by code (ties by id), and a range of the sorted list is split at
//! the highest bit in which its first and last codes differ (in the middle
//! where they are equal) until at most [`LEAF_TRIANGLES`] remain.
//!
//! Layout: the nodes in depth-first preorder, so a node's left child is the
//! next node; each node stores its *escape* index, the first node after its
//! subtree. A walk that visits every node whose box the ray meets needs no
//! stack: on a hit, step to the next node (or, at a leaf, test its
//! triangles and jump to the escape); on a miss, jump to the escape. The
//! walk ends at index `nodes.len()`. The ray cast wants every hit (nearest,
//! farthest and their count), so no front-to-back order is lost.
//!
//! Boxes are padded by a relative 2⁻²⁰ of their coordinates' magnitude (and
//! the ray–box test widens its interval, see `cpu.rs`), so a triangle the
//! watertight test would hit is never culled by a box rounding the other
//! way.

use glam::Vec3;

use crate::mesh::TriMesh;
use crate::{Error, Result};

/// Most triangles in one leaf (the leaf word keeps the count in 3 bits).
pub const LEAF_TRIANGLES: usize = 4;

/// Most triangles one hierarchy indexes (the leaf word keeps the first
/// triangle in 29 bits).
pub const MAX_TRIANGLES: usize = 1 << 29;

/// One node as the kernel reads it (32 bytes, `struct Node` in
/// `kernels/ray_cast.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    /// Box minimum (padded).
    pub lo: [f32; 3],
    /// First node after this node's subtree.
    pub escape: u32,
    /// Box maximum (padded).
    pub hi: [f32; 3],
    /// 0 for an inner node; for a leaf `first << 3 | count`: its triangles
    /// are `first..first + count` of [`Bvh::corners`] (in threes).
    pub leaf: u32,
}

impl Node {
    /// The leaf's triangle range (empty for an inner node).
    pub fn triangles(&self) -> std::ops::Range<usize> {
        let first = (self.leaf >> 3) as usize;
        first..first + (self.leaf & 7) as usize
    }
}

/// The hierarchy of one mesh.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bvh {
    /// Nodes in depth-first preorder (empty for a mesh without triangles).
    pub nodes: Vec<Node>,
    /// Three corners per triangle in leaf order, `[x, y, z, id]` with the
    /// mesh's triangle id in `w` as `f32::from_bits(id)`.
    pub corners: Vec<[f32; 4]>,
}

/// Spreads the low 10 bits of `v` to every third bit.
fn spread(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// `value` moved outward by 2⁻²⁰ of its magnitude (and at least by the
/// smallest normal f32), away from the box's inside.
fn pad(value: f32, outward: f32) -> f32 {
    value + outward * (value.abs() * (1.0 / (1 << 20) as f32) + f32::MIN_POSITIVE)
}

impl Bvh {
    /// Builds the hierarchy of `mesh`'s triangles.
    ///
    /// Errors: more than [`MAX_TRIANGLES`] triangles.
    pub fn build(mesh: &TriMesh) -> Result<Bvh> {
        let n = mesh.triangles.len();
        if n > MAX_TRIANGLES {
            return Err(Error::limit("ray_cast: BVH triangles", n, MAX_TRIANGLES));
        }
        if n == 0 {
            return Ok(Bvh::default());
        }
        let corners = |t: usize| mesh.triangles[t].map(|v| mesh.positions[v as usize]);
        let centroids: Vec<Vec3> = (0..n)
            .map(|t| {
                let [a, b, c] = corners(t);
                (a + b + c) / 3.0
            })
            .collect();
        let (lo, hi) = centroids
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(*c), hi.max(*c))
            });
        let scale = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        let mut order: Vec<(u32, u32)> = centroids
            .iter()
            .enumerate()
            .map(|(t, c)| {
                let q = ((*c - lo) / scale * 1023.0).clamp(Vec3::ZERO, Vec3::splat(1023.0));
                let code = spread(q.x as u32) << 2 | spread(q.y as u32) << 1 | spread(q.z as u32);
                (code, t as u32)
            })
            .collect();
        radsort::sort_by_key(&mut order, |&(code, t)| (code, t));
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * n / LEAF_TRIANGLES + 1),
            corners: Vec::with_capacity(3 * n),
        };
        for &(_, t) in &order {
            for p in corners(t as usize) {
                bvh.corners.push([p.x, p.y, p.z, f32::from_bits(t)]);
            }
        }
        let codes: Vec<u32> = order.iter().map(|&(code, _)| code).collect();
        bvh.emit(&codes, 0, n);
        Ok(bvh)
    }

    /// Emits the subtree over sorted triangles `start..end` in preorder and
    /// returns its (unpadded) box.
    fn emit(&mut self, codes: &[u32], start: usize, end: usize) -> (Vec3, Vec3) {
        let at = self.nodes.len();
        self.nodes.push(Node {
            lo: [0.0; 3],
            escape: 0,
            hi: [0.0; 3],
            leaf: 0,
        });
        let (lo, hi) = if end - start <= LEAF_TRIANGLES {
            self.nodes[at].leaf = (start as u32) << 3 | (end - start) as u32;
            self.corners[3 * start..3 * end].iter().fold(
                (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(lo, hi), p| {
                    let p = Vec3::new(p[0], p[1], p[2]);
                    (lo.min(p), hi.max(p))
                },
            )
        } else {
            let mid = split(codes, start, end);
            let (l_lo, l_hi) = self.emit(codes, start, mid);
            let (r_lo, r_hi) = self.emit(codes, mid, end);
            (l_lo.min(r_lo), l_hi.max(r_hi))
        };
        let escape = self.nodes.len() as u32;
        let node = &mut self.nodes[at];
        node.lo = lo.to_array().map(|v| pad(v, -1.0));
        node.hi = hi.to_array().map(|v| pad(v, 1.0));
        node.escape = escape;
        (lo, hi)
    }

    /// Number of triangles indexed.
    pub fn n_triangles(&self) -> usize {
        self.corners.len() / 3
    }

    /// Depth of the deepest leaf (the root has depth 0).
    pub fn depth(&self) -> usize {
        let mut depth = 0;
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, d)) = stack.pop() {
            let node = &self.nodes[i];
            depth = depth.max(d);
            if node.leaf == 0 {
                let left = i + 1;
                let right = self.nodes[left].escape as usize;
                stack.extend([(left, d + 1), (right, d + 1)]);
            }
        }
        depth
    }
}

/// Where the sorted range `start..end` (more than one triangle) splits:
/// after the last code that agrees with the first one in the highest
/// differing bit, or in the middle when all codes are equal.
fn split(codes: &[u32], start: usize, end: usize) -> usize {
    let (first, last) = (codes[start], codes[end - 1]);
    if first == last {
        return (start + end) / 2;
    }
    let bit = 31 - (first ^ last).leading_zeros();
    let prefix = first >> bit;
    start + codes[start..end].partition_point(|&c| c >> bit == prefix)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_interleaves() {
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x3ff), 0x0924_9249);
    }

    #[test]
    fn split_finds_the_highest_differing_bit() {
        let codes = [0b0001, 0b0010, 0b0100, 0b0101, 0b1000];
        assert_eq!(split(&codes, 0, 5), 4);
        assert_eq!(split(&codes, 0, 4), 2);
        assert_eq!(split(&[7, 7, 7, 7], 0, 4), 2);
    }
}
