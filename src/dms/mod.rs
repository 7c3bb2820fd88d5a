//! Quadratic DMS (Dahmen–Micchelli–Seidel) triangular B-spline surfaces
//! over knot clouds (seed 000 ch. 2; SPEC §2): a smooth skin over a
//! parametrised triangle mesh. Formulas, seed errors and decisions:
//! docs/design/dms.md.
//!
//! ```text
//!  TriMesh ──parametrise(cylinder | planar | given)──▶ uv per vertex (positive, repaired, no overlap)
//!  uv + triangles ──knot_clouds──▶ [t_i0, t_i1, t_i2] per vertex, smallest triple quality
//!  triangles + knots ──Domain──▶ shared controls (#V + E), knot hulls on a grid
//!  parameter triangles ──lattice(n)──▶ n points per edge, (n − 1)² triangles each
//!  lattice points ──dms_basis──▶ per point: weights [N, ∂N/∂u, ∂N/∂v] of its controls
//!  rows + control net (identify | quasi | least squares) ──dms_surface──▶ points + normals
//! ```
//!
//! [`oracle`] is the f64 reference (exact half-open rule, generic
//! recursion); [`basis`] and [`surface`] are the two kernels with their
//! f32 mirrors; [`spline()`] runs the whole chain, and
//! [`SplineDomain::skin`] redraws a changed mesh (a relaxation frame) with
//! two gathers.

pub mod basis;
pub mod domain;
pub mod fit;
pub mod knots;
pub mod lattice;
pub mod neighbourhood;
pub mod oracle;
pub mod param;
pub mod patch;
pub mod program;
pub mod spline;
pub mod surface;

pub use domain::Domain;
pub use knots::{KnotClouds, knot_clouds};
pub use lattice::{Lattice, LatticePoint, lattice, lattice_counts};
pub use param::{Parametrisation, Projection, parametrise};
pub use spline::{Fit, LiveSkin, SplineDomain, SplineOptions, SplineSurface, spline};
