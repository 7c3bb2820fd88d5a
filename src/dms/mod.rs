//! Quadratic DMS (Dahmen–Micchelli–Seidel) triangular B-spline surfaces
//! over knot clouds (seed 000 ch. 2; SPEC §2): a smooth skin over a
//! parametrised triangle mesh.
//!
//! The room is being built in steps (issue "DMS spline surfaces"; the
//! formulas, their checks and the open decisions are in
//! docs/design/dms.md). Built so far: the evaluation lattice of §2.5
//! ([`lattice()`]): `n` points per parameter edge, every vertex and edge
//! point numbered once, `(n − 1)²` output triangles per parameter triangle.
//!
//! ```text
//!  parameter triangles (ids) ──lattice(n)──▶ Lattice { points: (triangle, i, j), triangles }
//! ```

pub mod lattice;

pub use lattice::{Lattice, LatticePoint, lattice, lattice_counts};
