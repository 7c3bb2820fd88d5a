//! The host's uniform-grid cell list of particles (SPEC §3.2): a counting
//! sort of particle ids by cell, rebuilt when a particle has moved more than
//! half the skin since the build (two particles may approach each other by
//! twice that), or when a cutoff outgrows the one it was built for.
//!
//! A particle gathers over the 27 cells around its **build-time** cell, in
//! a fixed order (dz, dy, dx from −1 to 1; ids ascending within a cell), so
//! every pair within `cutoff` is found as long as the cell edge is at least
//! `cutoff + skin`. Tested equal to a brute-force search.

use glam::{UVec3, Vec3};

use crate::{Error, Result};

/// Most cells of a list (coarser cells beyond it: still exact, more candidates).
const MAX_CELLS_PER_PARTICLE: usize = 4;

/// A cell list over particle positions.
#[derive(Debug, Clone, PartialEq)]
pub struct CellList {
    /// World position of the grid's corner.
    pub origin: Vec3,
    /// Cell edge (≥ cutoff + skin).
    pub cell: f32,
    /// Cells per axis.
    pub dims: UVec3,
    /// #cells + 1 starts into `items`.
    pub starts: Vec<u32>,
    /// Particle ids sorted by cell, ascending within a cell.
    pub items: Vec<u32>,
    /// The build-time cell (linear index) of each particle.
    pub home: Vec<u32>,
    /// Positions at the build, for the rebuild test.
    built_at: Vec<Vec3>,
    /// The cutoff it was built for, and the skin.
    pub cutoff: f32,
    pub skin: f32,
}

impl CellList {
    /// Builds the list of `positions` for pairs within `cutoff`, with
    /// `skin` of slack for later moves.
    ///
    /// Errors: non-finite positions or a non-positive cutoff
    /// ([`Error::InvalidParameter`]), more particles than `u32` numbers.
    pub fn build(positions: &[Vec3], cutoff: f32, skin: f32) -> Result<CellList> {
        let n = positions.len();
        if !(cutoff.is_finite() && cutoff > 0.0 && skin.is_finite() && skin >= 0.0) {
            return Err(Error::param(
                "cell list cutoff, skin",
                format!("{cutoff}, {skin}"),
                "must be finite, the cutoff positive",
            ));
        }
        u32::try_from(n).map_err(|_| Error::limit("cell list particles", n, u32::MAX))?;
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::data(
                "cell list",
                "particle",
                i,
                "non-finite position",
            ));
        }
        let lo = positions.iter().fold(Vec3::INFINITY, |m, p| m.min(*p));
        let hi = positions.iter().fold(Vec3::NEG_INFINITY, |m, p| m.max(*p));
        let (lo, hi) = if n == 0 {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        };
        let extent = hi - lo;
        let mut cell = cutoff + skin;
        let count = |c: f32| (extent / c).floor().as_uvec3() + UVec3::ONE;
        let budget = (MAX_CELLS_PER_PARTICLE * n).max(1) as f64;
        while count(cell).as_dvec3().element_product() > budget {
            cell *= 1.25;
        }
        let dims = count(cell);
        let n_cells = (dims.x * dims.y * dims.z) as usize;
        let inv = 1.0 / cell;
        let home: Vec<u32> = positions
            .iter()
            .map(|p| {
                let c = ((*p - lo) * inv).floor().as_uvec3().min(dims - UVec3::ONE);
                c.x + dims.x * (c.y + dims.y * c.z)
            })
            .collect();
        let mut starts = vec![0u32; n_cells + 1];
        for &h in &home {
            starts[h as usize + 1] += 1;
        }
        for k in 0..n_cells {
            starts[k + 1] += starts[k];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; n];
        for (i, &h) in home.iter().enumerate() {
            items[fill[h as usize] as usize] = i as u32;
            fill[h as usize] += 1;
        }
        Ok(CellList {
            origin: lo,
            cell,
            dims,
            starts,
            items,
            home,
            built_at: positions.to_vec(),
            cutoff,
            skin,
        })
    }

    /// Whether the list still finds every pair within `cutoff` at
    /// `positions` (the same particles): no cutoff beyond the built one, no
    /// particle moved more than half the skin.
    pub fn still_valid(&self, positions: &[Vec3], cutoff: f32) -> bool {
        positions.len() == self.built_at.len()
            && cutoff <= self.cutoff
            && (positions.iter().zip(&self.built_at))
                .all(|(p, q)| p.distance_squared(*q) <= 0.25 * self.skin * self.skin)
    }

    /// The cells around particle `i`'s build-time cell, in gather order.
    pub fn around(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let h = self.home[i];
        let d = self.dims;
        let c = UVec3::new(h % d.x, (h / d.x) % d.y, h / (d.x * d.y)).as_ivec3();
        (-1..=1).flat_map(move |dz| {
            (-1..=1).flat_map(move |dy| {
                (-1..=1).filter_map(move |dx| {
                    let q = c + glam::IVec3::new(dx, dy, dz);
                    let inside = q.cmpge(glam::IVec3::ZERO).all() && q.cmplt(d.as_ivec3()).all();
                    inside.then(|| (q.x as u32 + d.x * (q.y as u32 + d.y * q.z as u32)) as usize)
                })
            })
        })
    }

    /// Candidate neighbours of particle `i` (itself excluded), in gather order.
    pub fn candidates(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.around(i)
            .flat_map(move |c| {
                self.items[self.starts[c] as usize..self.starts[c + 1] as usize].iter()
            })
            .map(|&j| j as usize)
            .filter(move |&j| j != i)
    }

    /// The flat `u32` buffer of the kernels: starts, items, home cells.
    pub fn flat(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.starts.len() + 2 * self.items.len());
        out.extend(&self.starts);
        out.extend(&self.items);
        out.extend(&self.home);
        out
    }
}
