//! Polyhedrization of non-convex digital objects (seed 003 §4.2–4.5).
//!
//! So far: the background components inside the convex hull (ZKH, §4.2.1),
//! their classification by the hull faces they touch (Def. CO/CA/TU,
//! §4.2.3), and the face selection for pressing-in (Def. PR (i)–(iii)) —
//! the inputs of the modification steps (building CH(S' ∪ M), recursion
//! with swapped roles, merging cell lists), which are not built yet.

pub mod press;
pub mod zkh;

pub use press::faces_to_press;
pub use zkh::{Zkh, ZkhClass, background_components};
