//! Polyhedrization of non-convex digital objects (seed 003 §4.2–4.5).
//!
//! - [`zkh`]: the background components inside the convex hull (ZKH,
//!   §4.2.1) and their classes by the hull faces they touch (Def. CO/CA/TU,
//!   §4.2.3).
//! - [`polyhedrize()`]: the lossless representation — the recursion with
//!   swapped roles of §4.4 as a tree of convex shells, cavities as reversed
//!   shells, genus > 0 components as maximal digital balls ([`balls`],
//!   §4.5.4), exact voxelization, storage (eq. 8.2) and `.cells` files.
//! - [`press`]: the face selection for pressing-in (Def. PR (i)–(iii)).
//! - [`surface`]: the single merged surface of §4.4.1 ("Zusammenfügen"),
//!   by exact boundary evaluation of the shells' face chain, with its
//!   convex faces (Theorem KE, §4.5.6).
//! - [`inside`]: point-in-polyhedron for the non-convex merged surface by
//!   exact ray parity (§4.4.3), and the voxelization it gives.

pub mod balls;
mod cellfile;
pub mod inside;
pub mod polyhedrize;
pub mod press;
pub mod surface;
pub mod zkh;

pub use polyhedrize::{
    PolyhedrizeOptions, Polyhedron, PolyhedronSummary, Role, Shell, ShellGeometry, ShellKind,
    ZkhReport, polyhedrize,
};
pub use press::faces_to_press;
pub use surface::{ConvexFace, MergedFace, MergedSurface, theorem_ke};
pub use zkh::{Zkh, ZkhClass, background_components};
