//! Digital objects: sets of voxels selected from a [`Volume`], seen as
//! subcomplexes of a 3-D abstract cell complex (seed 003 ch. 2, §3.1, §4.1).
//!
//! Combinatorial (Kovalevsky) coordinates: voxel `(i, j, k)` of the source
//! volume is the 3-cell with coordinates `(2i+1, 2j+1, 2k+1)` (all odd); its
//! lowest corner is the 0-cell `(2i, 2j, 2k)` (all even); mixed parities are
//! the 1- and 2-cells. All coordinates are `i64`.
//!
//! The object is one 6-connected component (strong connectivity, §3.1) or the
//! union of all of them. Configurations where object voxels meet only along
//! an edge or at a vertex make the boundary non-manifold; see
//! [`topology`] for the policy (they are counted and the boundary is opened
//! there, as if the object were the 6-connected set it is).

pub mod corners;
pub mod topology;

use crate::volume::{Volume, VolumeData, analysis::label_6_connected};

pub use corners::CandidateKind;
pub use topology::BoundaryTopology;

/// A digital object in figures: voxels, boundary facets (2-cells between
/// S and its complement), inclusive voxel bounding box (source indices).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ObjectFigures {
    pub voxels: u64,
    pub boundary_facets: u64,
    pub voxel_bbox: ([i64; 3], [i64; 3]),
}

/// Combinatorial coordinates of the centre of voxel `v` (voxel indices).
pub fn voxel_centre(v: [i64; 3]) -> [i64; 3] {
    v.map(|c| 2 * c + 1)
}

/// Combinatorial coordinates of the lowest corner (0-cell) of voxel `v`.
pub fn voxel_corner(v: [i64; 3]) -> [i64; 3] {
    v.map(|c| 2 * c)
}

/// Which voxels of a volume form the object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Selection {
    /// Samples `≥ T`.
    Threshold(f64),
    /// Samples `== L`.
    Label(f64),
}

/// Which 6-connected components of the selection form the object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// The component with the most voxels (ties: the first in file order).
    Largest,
    /// All selected voxels.
    All,
    /// Component `N` (1-based) in file order, numbered as
    /// [`label_6_connected`] does (order of each component's first voxel,
    /// x fastest).
    Index(usize),
}

/// Placement of voxel indices in the world: voxel `(i, j, k)` has its centre
/// at `origin + Σ_k spacing[k]·index_k·axes[k]` (as [`Volume::world`]), so
/// combinatorial coordinate `c` maps to the index `(c − 1)/2`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Distance between voxel centres per axis (world units).
    pub spacing: [f64; 3],
    /// World position of the centre of voxel `(0, 0, 0)`.
    pub origin: [f64; 3],
    /// World direction of each index axis (orthonormal).
    pub axes: [[f64; 3]; 3],
}

impl Frame {
    /// The frame of `volume`'s samples.
    pub fn of(volume: &Volume) -> Frame {
        Frame {
            spacing: volume.spacing,
            origin: volume.origin,
            axes: volume.axes,
        }
    }

    /// World position of combinatorial coordinates `c`.
    pub fn world(&self, c: [i64; 3]) -> [f64; 3] {
        let index: [f64; 3] = std::array::from_fn(|a| (c[a] as f64 - 1.0) / 2.0);
        std::array::from_fn(|w| {
            self.origin[w]
                + (0..3)
                    .map(|a| self.spacing[a] * index[a] * self.axes[a][w])
                    .sum::<f64>()
        })
    }

    /// Whether the axes include a reflection (surfaces built in index space
    /// need their winding reversed in the world).
    pub fn reflects(&self) -> bool {
        crate::volume::reflects(&self.axes)
    }

    /// [`Frame::world`] as an `f32` mesh position.
    pub fn world_f32(&self, c: [i64; 3]) -> glam::Vec3 {
        let w = self.world(c);
        glam::Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
    }
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            spacing: [1.0; 3],
            origin: [0.0; 3],
            axes: crate::volume::IDENTITY_AXES,
        }
    }
}

/// A set S of voxels, stored as a mask over its bounding box plus a
/// one-voxel background margin.
#[derive(Debug, Clone, PartialEq)]
pub struct DigitalObject {
    /// Source-volume voxel index of mask voxel `(0, 0, 0)` (the margin, so
    /// usually the object's minimum minus one).
    low: [i64; 3],
    /// Mask dimensions (object bounding box + 2 per axis).
    dims: [usize; 3],
    /// `dims[0]·dims[1]·dims[2]` flags, x fastest.
    mask: Vec<bool>,
    n_voxels: u64,
    frame: Frame,
}

impl DigitalObject {
    /// Selects the object from `volume`: samples passing `selection`, then the
    /// 6-connected `component`(s).
    ///
    /// Errors: [`crate::Refusal::EmptySelection`] when nothing is selected,
    /// [`crate::Error::InvalidParameter`] when component `N` does not exist.
    pub fn from_volume(
        volume: &Volume,
        selection: Selection,
        component: Component,
    ) -> crate::Result<DigitalObject> {
        let keep = select(&volume.data, selection);
        let frame = Frame::of(volume);
        let chosen: Vec<bool> = match component {
            Component::All => keep,
            Component::Largest | Component::Index(_) => {
                let lab = label_6_connected(volume.dims, |i| keep[i])?;
                let want = match component {
                    Component::Index(n) if n >= 1 && n <= lab.n_components() => n as u32,
                    Component::Index(n) => {
                        return Err(crate::Error::param(
                            "component",
                            n,
                            format!(
                                "does not exist: the selection has {} 6-connected components",
                                lab.n_components()
                            ),
                        ));
                    }
                    _ => {
                        let mut best = 0usize;
                        for (c, &s) in lab.sizes.iter().enumerate() {
                            if s > lab.sizes[best] {
                                best = c;
                            }
                        }
                        best as u32 + 1
                    }
                };
                lab.labels.iter().map(|&l| l == want && want > 0).collect()
            }
        };
        DigitalObject::from_mask(volume.dims, &chosen, frame)
    }

    /// The object of the `true` voxels of a `dims` mask (x fastest).
    ///
    /// Errors: [`crate::Error::Mismatch`] when the mask length does not
    /// match `dims`, [`crate::Refusal::EmptySelection`] when no voxel is set.
    pub fn from_mask(
        dims: [usize; 3],
        mask: &[bool],
        frame: Frame,
    ) -> crate::Result<DigitalObject> {
        let n = dims.iter().product::<usize>();
        if n != mask.len() {
            return Err(crate::Error::mismatch(
                format!("mask voxels (dims {dims:?})"),
                n,
                mask.len(),
            ));
        }
        let mut lo = [usize::MAX; 3];
        let mut hi = [0usize; 3];
        let mut n_voxels = 0u64;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                let row = dims[0] * (y + dims[1] * z);
                for x in 0..dims[0] {
                    if mask[row + x] {
                        n_voxels += 1;
                        for (a, c) in [x, y, z].into_iter().enumerate() {
                            lo[a] = lo[a].min(c);
                            hi[a] = hi[a].max(c);
                        }
                    }
                }
            }
        }
        if n_voxels == 0 {
            return Err(crate::Refusal::EmptySelection {
                what: "voxel selection".into(),
                detail: "no voxel is selected".into(),
            }
            .into());
        }
        let low = lo.map(|c| c as i64 - 1);
        let odims: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a] + 3);
        let mut out = vec![false; odims.iter().product()];
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let src = dims[0] * (y + dims[1] * z);
                let dst = odims[0] * (y - lo[1] + 1 + odims[1] * (z - lo[2] + 1)) + 1;
                out[dst..dst + hi[0] - lo[0] + 1].copy_from_slice(&mask[src + lo[0]..=src + hi[0]]);
            }
        }
        Ok(DigitalObject {
            low,
            dims: odims,
            mask: out,
            n_voxels,
            frame,
        })
    }

    /// The same object with voxel indices moved by `offset` (for masks cut
    /// out of a larger volume: local voxel `v` becomes `v + offset`); the
    /// frame is the caller's.
    pub fn shifted(mut self, offset: [i64; 3]) -> DigitalObject {
        for (l, o) in self.low.iter_mut().zip(offset) {
            *l += o;
        }
        self
    }

    /// Number of voxels (3-cells) in S.
    pub fn n_voxels(&self) -> u64 {
        self.n_voxels
    }

    /// Voxels, boundary facets and voxel box: the `object` entry of the
    /// hull, scan and polyhedrize reports.
    pub fn figures(&self) -> ObjectFigures {
        ObjectFigures {
            voxels: self.n_voxels(),
            boundary_facets: self.n_boundary_facets(),
            voxel_bbox: self.voxel_bbox(),
        }
    }

    /// Inclusive voxel-index bounding box of S in the source volume.
    pub fn voxel_bbox(&self) -> ([i64; 3], [i64; 3]) {
        (
            self.low.map(|c| c + 1),
            std::array::from_fn(|a| self.low[a] + self.dims[a] as i64 - 2),
        )
    }

    /// World placement of the source volume.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// Whether voxel `v` (source-volume voxel indices) belongs to S; `false`
    /// outside the stored box.
    pub fn contains(&self, v: [i64; 3]) -> bool {
        let l: [i64; 3] = std::array::from_fn(|a| v[a] - self.low[a]);
        if (0..3).any(|a| l[a] < 0 || l[a] >= self.dims[a] as i64) {
            return false;
        }
        self.mask[l[0] as usize + self.dims[0] * (l[1] as usize + self.dims[1] * l[2] as usize)]
    }

    /// Every voxel of S, in file order (x fastest), as source voxel indices.
    pub fn voxels(&self) -> impl Iterator<Item = [i64; 3]> + '_ {
        let [nx, ny, _] = self.dims;
        self.mask
            .iter()
            .enumerate()
            .filter(|(_, in_s)| **in_s)
            .map(move |(i, _)| {
                let l = [i % nx, (i / nx) % ny, i / (nx * ny)];
                std::array::from_fn(|a| self.low[a] + l[a] as i64)
            })
    }

    /// Number of boundary facets: 2-cells between a voxel of S and a
    /// background voxel (the seed's "Facetten"; marching cubes makes about
    /// two triangles per facet, eq. 8.1).
    pub fn n_boundary_facets(&self) -> u64 {
        let [nx, ny, nz] = self.dims;
        let strides = [1, nx, nx * ny];
        let mut n = 0u64;
        for z in 1..nz - 1 {
            for y in 1..ny - 1 {
                for x in 1..nx - 1 {
                    let i = x + nx * (y + ny * z);
                    if self.mask[i] {
                        for s in strides {
                            n += u64::from(!self.mask[i - s]) + u64::from(!self.mask[i + s]);
                        }
                    }
                }
            }
        }
        n
    }

    /// Local mask dimensions and flags, for the topology and corner scans.
    fn raw(&self) -> ([usize; 3], &[bool], [i64; 3]) {
        (self.dims, &self.mask, self.low)
    }
}

/// Marching-cubes storage estimate, eq. 8.1: `3·N_V + 3·N_T = 4.5·N_T`
/// integers for `n_triangles` triangles (`N_V ≈ N_T/2`).
pub fn marching_cubes_integers(n_triangles: u64) -> u64 {
    n_triangles * 9 / 2
}

fn select(data: &VolumeData, selection: Selection) -> Vec<bool> {
    let keep = move |v: f64| match selection {
        Selection::Threshold(t) => v >= t,
        Selection::Label(l) => v == l,
    };
    (0..data.len()).map(|i| keep(data.get_f64(i))).collect()
}
