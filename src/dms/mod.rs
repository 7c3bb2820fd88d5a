//! Quadratic DMS (Dahmen–Micchelli–Seidel) triangular B-spline surfaces
//! over knot clouds (seed 000 ch. 2; SPEC §2): a smooth skin over a
//! parametrised triangle mesh.
//!
//! The room is being built in steps (issue "DMS spline surfaces"; the
//! formulas, their checks and the open decisions are in
//! docs/design/dms.md). Built so far: the parametrisation of §2.1
//! ([`parametrise`]), the knot clouds of §2.2 ([`knot_clouds`]), the f64
//! oracle of the basis of §2.3 ([`oracle`]) and the evaluation lattice of
//! §2.5 ([`lattice()`]):
//! `n` points per parameter edge, every vertex and edge point numbered
//! once, `(n − 1)²` output triangles per parameter triangle.
//!
//! ```text
//!  TriMesh ──parametrise(cylinder | planar | given)──▶ uv per vertex (positive, repaired, no overlap)
//!  uv + triangles ──knot_clouds──▶ [t_i0, t_i1, t_i2] per vertex, smallest triple quality
//!  u + a triangle's clouds ──oracle::bsplines──▶ the six N_β(u) (f64, exact half-open rule)
//!  parameter triangles ──lattice(n)──▶ Lattice { points: (triangle, i, j), triangles }
//! ```

pub mod knots;
pub mod lattice;
pub mod oracle;
pub mod param;

pub use knots::{KnotClouds, knot_clouds};
pub use lattice::{Lattice, LatticePoint, lattice, lattice_counts};
pub use param::{Parametrisation, Projection, parametrise};
