//! The foundation: building blocks every other layer uses, one copy each.
//! Nothing here knows a mesh type, a volume, the GPU or an algorithm room.
//!
//! - [`union_find`]: sequential and concurrent union-find (smallest root),
//!   connected components of a triangle soup;
//! - [`aabb`], [`forest`]: axis-aligned boxes and the bounding-box B+ forest,
//!   the crate's spatial index (cutting, self-intersection, marching cubes);
//! - [`exact`]: exact integer geometry (i64 vectors with i128 products, gcd,
//!   orientation) and exact orientation signs of f64 points;
//! - [`fs`]: atomic file writes and output path checks;
//! - [`report`]: the typed JSON reports of operations (a schema each).

pub mod aabb;
pub mod alloc;
pub mod exact;
pub mod forest;
pub mod fs;
pub mod report;
pub mod union_find;

pub use aabb::Aabb;
pub use forest::{CellNode, Forest, GroupNode, GroupedForest, LayerNode, MeshView, RowNode, Span};
pub use union_find::{AtomicUnionFind, UnionFind, vertex_components};
