//! Particles on skeletal implicit surfaces (SPEC §3.2–3.3, seed 002 §3.2–4.4):
//! Witkin–Heckbert particle sampling ([`wh`]) over the host's cell list
//! ([`cells`]).
//!
//! ```text
//!  Scene ─pose(t)─▶ FieldInput ─┐
//!  start: projected marching-cubes vertices ─▶ Particles ─▶ Sampler::iterate
//!        host: cell list (rebuild on skin/2)          │ kernel particle_update
//!        host: fission, death, lost (WH94 rule)  ◀────┘ (mirror: wh::cpu)
//! ```
//!
//! Design notes, derivations and defaults: `docs/design/particles.md`.

pub mod animate;
pub mod cells;
pub mod network;
pub mod wh;

pub use cells::CellList;
pub use network::{Network, NetworkOptions};
pub use wh::{Particles, Sampler, WhOptions};

/// One step's outputs of `particle_update` or `network_update`: new
/// positions (and σ) and the per-particle state or field sample.
pub type StepOutput = (Vec<[f32; 4]>, Vec<[f32; 4]>);
