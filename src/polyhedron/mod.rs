//! Polyhedrization of non-convex digital objects (seed 003 §4.2–4.5).
//!
//! So far: the background components inside the convex hull (ZKH, §4.2.1)
//! and their classification by the hull faces they touch (Def. CO/CA/TU,
//! §4.2.3) — the input of the modification steps (pressing-in, cavities,
//! tunnels), which are not built yet.

pub mod zkh;

pub use zkh::{Zkh, ZkhClass, background_components};
