//! Chunk *stitching*: takes the chunks' groupings ([`ChunkGroups`]) and the
//! triangles' and vertices' chunk-local union-find nodes, and returns every
//! triangle's and vertex's canonical group (numbered by first triangle) and
//! the number of groups.

use rayon::prelude::*;

use super::emit::ChunkGroups;
use super::{NONE, own_end};
use crate::foundation::UnionFind;

/// Joins the chunks' grouping: one union-find over all chunks' nodes, the
/// vertices of each shared layer united, then `groups` (per triangle: the
/// chunk-local node on entry) becomes the canonical group, numbered by
/// first triangle, and so does `vertex_groups` (per vertex: the node of
/// the chunk that owns it; NONE, for a vertex no triangle uses, stays).
/// Returns the number of groups.
pub(super) fn stitch(
    chunk_groups: &[ChunkGroups],
    chunks: &[(usize, usize)],
    vbase: &[u32],
    tbase: &[u32],
    groups: &mut [u32],
    vertex_groups: &mut [u32],
) -> usize {
    let mut node_base = Vec::with_capacity(chunk_groups.len());
    let mut n_nodes = 0u32;
    for c in chunk_groups {
        node_base.push(n_nodes);
        n_nodes += c.uf.len() as u32;
    }
    let mut uf = UnionFind::default();
    for c in chunk_groups {
        uf.append(&c.uf);
    }
    // Seams: chunk k's first layer (which it owns) is chunk k − 1's last.
    for k in 1..chunk_groups.len() {
        let z = chunks[k].0;
        let own = &vertex_groups[vbase[z] as usize..vbase[z + 1] as usize];
        for (&a, &b) in chunk_groups[k - 1].seam_node.iter().zip(own) {
            if a != NONE && b != NONE {
                uf.union(node_base[k - 1] + a, node_base[k] + b);
            }
        }
    }
    // A node is made by the triangle that starts it, so nodes are numbered
    // in triangle order (chunk by chunk), and a set's root, its smallest
    // node, was made by its first triangle: the canonical numbers (by
    // first triangle) are the roots' ranks, found without walking the
    // triangles. A root comes before its members, so one ascending pass
    // gives every node its group.
    let mut group = uf.roots();
    let mut n_groups = 0u32;
    for n in 0..group.len() {
        let r = group[n] as usize;
        group[n] = if r == n {
            n_groups += 1;
            n_groups - 1
        } else {
            group[r]
        };
    }
    // Per chunk, each triangle's local node to its group.
    let mut slices = Vec::with_capacity(chunks.len());
    let mut rest = groups;
    for &(z0, z1) in chunks {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((tbase[z1] - tbase[z0]) as usize);
        slices.push(head);
        rest = tail;
    }
    slices
        .into_par_iter()
        .zip(&node_base)
        .for_each(|(tris, &base)| {
            for g in tris.iter_mut() {
                *g = group[(base + *g) as usize];
            }
        });
    // Vertices: chunk k owns layers z0 up to the next chunk's first.
    let mut owned = Vec::with_capacity(chunks.len());
    let mut rest = vertex_groups;
    for (k, &(z0, _)) in chunks.iter().enumerate() {
        let end = vbase[own_end(chunks, k, vbase.len() - 1)];
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((end - vbase[z0]) as usize);
        owned.push(head);
        rest = tail;
    }
    owned
        .into_par_iter()
        .zip(&node_base)
        .for_each(|(vertices, &base)| {
            for g in vertices.iter_mut().filter(|g| **g != NONE) {
                *g = group[(base + *g) as usize];
            }
        });
    n_groups as usize
}
