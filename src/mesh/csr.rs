//! Compressed sparse row (CSR) adjacency: for each of `n` rows, a run of
//! `u32` neighbours in `targets[offsets[i]..offsets[i + 1]]`.

/// CSR adjacency with `offsets.len() == n_rows + 1`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Csr {
    /// #rows + 1 running offsets into `targets`, starting at 0.
    pub offsets: Vec<u32>,
    /// Concatenated neighbour lists.
    pub targets: Vec<u32>,
}

impl Csr {
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Neighbours of row `i`, in stored order.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.targets[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Builds rows from `(row, target)` pairs; targets keep their input order
    /// within a row (counting sort, O(n + m)).
    pub fn from_pairs(n_rows: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Self {
        let mut counts = vec![0u32; n_rows + 1];
        for (r, _) in pairs.clone() {
            counts[r as usize + 1] += 1;
        }
        for i in 0..n_rows {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut cursor = counts;
        let mut targets = vec![0u32; offsets[n_rows] as usize];
        for (r, t) in pairs {
            let slot = &mut cursor[r as usize];
            targets[*slot as usize] = t;
            *slot += 1;
        }
        Csr { offsets, targets }
    }

    /// Rows `range` alone, offsets rebased to start at 0.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Csr {
        let (lo, hi) = (self.offsets[range.start], self.offsets[range.end]);
        Csr {
            offsets: self.offsets[range.start..=range.end]
                .iter()
                .map(|o| o - lo)
                .collect(),
            targets: self.targets[lo as usize..hi as usize].to_vec(),
        }
    }

    /// Rows given as lists, kept in order.
    pub fn from_rows(rows: &[Vec<u32>]) -> Self {
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        offsets.push(0u32);
        let mut targets = Vec::with_capacity(rows.iter().map(Vec::len).sum());
        for r in rows {
            targets.extend_from_slice(r);
            offsets.push(targets.len() as u32);
        }
        Csr { offsets, targets }
    }

    /// Vertex → incident triangle adjacency of a triangle list over
    /// `n_vertices` vertices; each row lists triangle ids in increasing order
    /// (a triangle using a vertex twice is listed once per use).
    pub fn vertex_triangles(n_vertices: usize, triangles: &[[u32; 3]]) -> Self {
        Csr::from_pairs(
            n_vertices,
            triangles
                .iter()
                .enumerate()
                .flat_map(|(t, tri)| tri.iter().map(move |&v| (v, t as u32))),
        )
    }
}
