//! The 2-dimensional cell list of a polyhedron surface (seed App. C,
//! Kovalevsky 2002) and its compact integer encoding (eq. 8.2).
//!
//! Indices are 0-based; an edge reference is signed and 1-based
//! (`±(edge + 1)`) exactly as in Tables C.1 and C.3, so the sign is never
//! ambiguous.

use std::collections::HashMap;

use super::HalfSpace;

/// A 0-cell: coordinates and signed incident edges (`+(e+1)` when edge `e`
/// ends here, `−(e+1)` when it starts here; Table C.1).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Vertex0 {
    /// Combinatorial coordinates.
    pub coords: [i64; 3],
    /// Signed 1-based edge references.
    pub edges: Vec<i64>,
}

/// A 1-cell: start and end 0-cells and the faces on its left and right seen
/// from outside (Table C.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Edge1 {
    /// Start vertex.
    pub start: u32,
    /// End vertex.
    pub end: u32,
    /// Face to the left of start→end, seen from outside.
    pub left: u32,
    /// Face to the right.
    pub right: u32,
}

/// A 2-cell: its boundary as a closed sequence of (vertex, signed edge)
/// pairs, counter-clockwise from outside; the edge of a pair starts at its
/// vertex along the cycle (Table C.3). Plus its plane.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Face2 {
    /// `(vertex, ±(edge + 1))` pairs.
    pub boundary: Vec<(u32, i64)>,
    /// Outward supporting plane.
    pub plane: HalfSpace,
}

/// The cell list: three sub-lists for the 0-, 1- and 2-cells.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct CellList {
    /// 0-cells.
    pub vertices: Vec<Vertex0>,
    /// 1-cells.
    pub edges: Vec<Edge1>,
    /// 2-cells.
    pub faces: Vec<Face2>,
}

impl CellList {
    /// Builds the list from vertex coordinates and faces (vertex cycles CCW
    /// from outside, each undirected edge in exactly two faces, opposite
    /// directions). Edges are numbered in order of first appearance.
    pub fn from_faces<'a>(
        coords: &[[i64; 3]],
        faces: impl Iterator<Item = (&'a [u32], HalfSpace)>,
    ) -> CellList {
        let mut vertices: Vec<Vertex0> = coords
            .iter()
            .map(|&c| Vertex0 {
                coords: c,
                edges: Vec::new(),
            })
            .collect();
        let mut edges: Vec<Edge1> = Vec::new();
        let mut index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut out = Vec::new();
        for (f, (cycle, plane)) in faces.enumerate() {
            let f = f as u32;
            let mut boundary = Vec::with_capacity(cycle.len());
            for k in 0..cycle.len() {
                let (u, w) = (cycle[k], cycle[(k + 1) % cycle.len()]);
                let signed = if let Some(&e) = index.get(&(w, u)) {
                    edges[e as usize].right = f;
                    -(i64::from(e) + 1)
                } else {
                    let e = edges.len() as u32;
                    edges.push(Edge1 {
                        start: u,
                        end: w,
                        left: f,
                        right: u32::MAX,
                    });
                    index.insert((u, w), e);
                    vertices[u as usize].edges.push(-(i64::from(e) + 1));
                    vertices[w as usize].edges.push(i64::from(e) + 1);
                    i64::from(e) + 1
                };
                boundary.push((u, signed));
            }
            out.push(Face2 { boundary, plane });
        }
        CellList {
            vertices,
            edges,
            faces: out,
        }
    }

    /// Euler characteristic V − E + F (2 for a closed genus-0 surface).
    pub fn euler(&self) -> i64 {
        self.vertices.len() as i64 - self.edges.len() as i64 + self.faces.len() as i64
    }

    /// Storage estimate of eq. 8.2: `3·N_V + 5·N_F` integers.
    pub fn integers_eq_8_2(&self) -> usize {
        3 * self.vertices.len() + 5 * self.faces.len()
    }

    /// The non-redundant compact encoding: `[N_V, N_F, x y z per vertex,
    /// then per face k and its k vertex indices]`; edges and incidences
    /// follow from the face cycles.
    pub fn encode_compact(&self) -> Vec<i64> {
        let mut out = vec![self.vertices.len() as i64, self.faces.len() as i64];
        for v in &self.vertices {
            out.extend_from_slice(&v.coords);
        }
        for f in &self.faces {
            out.push(f.boundary.len() as i64);
            out.extend(f.boundary.iter().map(|&(v, _)| i64::from(v)));
        }
        out
    }

    /// Rebuilds the cell list from [`CellList::encode_compact`] output
    /// (planes recomputed from the first three vertices of each face, which
    /// are never collinear on a hull).
    ///
    /// Errors: [`crate::Error::InvalidData`] naming the integer, on
    /// truncated or inconsistent data.
    pub fn decode_compact(data: &[i64]) -> crate::Result<CellList> {
        let bad =
            |at: usize, what: &str| crate::Error::data("compact cell list", "integer", at, what);
        let pos = std::cell::Cell::new(0usize);
        let next = |what: &str| {
            let at = pos.get();
            pos.set(at + 1);
            data.get(at)
                .copied()
                .ok_or_else(|| bad(at, &format!("the list ends where the {what} was expected")))
        };
        let last = || pos.get() - 1;
        let n_v = usize::try_from(next("vertex count")?)
            .map_err(|_| bad(last(), "negative vertex count"))?;
        let n_f =
            usize::try_from(next("face count")?).map_err(|_| bad(last(), "negative face count"))?;
        let mut coords = Vec::with_capacity(n_v.min(data.len()));
        for _ in 0..n_v {
            coords.push([
                next("coordinate")?,
                next("coordinate")?,
                next("coordinate")?,
            ]);
        }
        let mut cycles = Vec::with_capacity(n_f.min(data.len()));
        for _ in 0..n_f {
            let k = usize::try_from(next("face size")?)
                .map_err(|_| bad(last(), "negative face size"))?;
            if k < 3 {
                return Err(bad(last(), "face with fewer than 3 vertices"));
            }
            let mut cycle = Vec::with_capacity(k.min(data.len()));
            for _ in 0..k {
                let v = next("face vertex")?;
                if v < 0 || v as usize >= n_v {
                    return Err(bad(last(), "vertex index out of range"));
                }
                cycle.push(v as u32);
            }
            cycles.push(cycle);
        }
        let planes: Vec<HalfSpace> = cycles
            .iter()
            .map(|c| {
                let p = |i: usize| coords[c[i] as usize];
                let n = super::primitive(super::cross(
                    super::sub(p(1), p(0)),
                    super::sub(p(c.len() - 1), p(0)),
                ));
                HalfSpace {
                    normal: n,
                    offset: super::dot(n, p(0)),
                }
            })
            .collect();
        Ok(CellList::from_faces(
            &coords,
            cycles.iter().map(|c| c.as_slice()).zip(planes),
        ))
    }
}
