//! chisel: a GPU compute engine for surgical-planning geometry.
//!
//! Five layers; dependencies point down only (docs/ARCHITECTURE.md):
//!
//! ```text
//!  ⑤ application   cli, render
//!  ④ rooms         vertex_normals reduce exclusive_scan mc hull_scan hull polyhedron cut tissue dms implicit particles blobby
//!  ③ GPU, parity   gpu (context, Backend, kernel specs, pass builder, buffers), parity (Tolerance, comparators)
//!  ② host data     mesh volume voxel io phantom
//!  ① foundation    foundation (union-find, boxes and forest, exact geometry, files), error
//! ```
//!
//! Data flows one way:
//!
//! ```text
//!  files ──io──▶ TriMesh / Volume (host topology: CSR, edge maps, components)
//!                   │ flatten to Pod arrays
//!                   ▼
//!            GpuArray uploads ──▶ kernels/*.wgsl ──▶ readback of what the host needs
//!                   │                                   │
//!                   └──── CPU mirror (same loop, f32) ──┴──▶ parity comparison
//!                                                      ▼
//!                         render (shaders/*.wgsl) ──▶ PNG previews, JSON reports
//! ```
//!
//! Every kernel is reachable through [`Backend::Cpu`] and [`Backend::Gpu`];
//! `tests/parity/` proves they agree.

pub mod blobby;
#[cfg(feature = "cli")]
pub mod cli;
pub mod cut;
pub mod dms;
pub mod error;
pub mod exclusive_scan;
pub mod foundation;
pub mod fusion;
pub mod gpu;
pub mod hull;
pub mod hull_scan;
pub mod implicit;
pub mod io;
pub mod mc;
pub mod mesh;
pub mod parity;
pub mod particles;
pub mod phantom;
pub mod polyhedron;
pub mod ray_cast;
pub mod reduce;
pub mod render;
pub mod tissue;
pub mod vertex_normals;
pub mod volume;
pub mod volume_scan;
pub mod voxel;

pub use error::{Error, Position, Refusal, Result};
pub use gpu::Backend;
pub use gpu::Gpu;
pub use mesh::TriMesh;
pub use volume::Volume;
