//! Layered spring model of facial soft tissue (seed 000 ch. 4, §5.2.1,
//! App. B; SPEC §1): network construction over the skull, surgery plans,
//! relaxation on the CPU mirror or the GPU, and an accelerated equilibrium
//! solver.
//!
//! ```text
//! TriMesh (epidermis) [+ TriMesh (bone)] ──SpringNetwork::build──▶ SpringNetwork
//!     (layers, 5 spring classes, eq. 4.1 k-d tree links, CSR on the host)
//! Volume (CT) ──ct::layers_from_ct (marching cubes)──▶ epidermis + bone
//! bone + Plan.cuts ──fragments::cut_bone (scalpels, caps)──▶ bone + Fragments
//! Plan (TOML/JSON) ──Plan::resolve(network, fragments)──▶ ResolvedPlan
//! relax(network, plan, options, Backend) ──▶ RelaxReport
//!     per increment: bone targets → K iterations of spring_step /
//!     spring_chebyshev → tissue_reduce_max → 8-byte readback → stop test
//! ```
//!
//! Kernels and mirrors (one name each):
//! `kernels/spring_step.wgsl` ↔ [`cpu::spring_step`] (eq. 4.4–4.7),
//! `kernels/spring_chebyshev.wgsl` ↔ [`cpu::spring_chebyshev`],
//! `kernels/tissue_reduce_max.wgsl` ↔ [`cpu::tissue_reduce_max`];
//! [`oracle`] is the independent f64 reference.
//!
//! The kernels and mirrors keep the state as displacements from rest,
//! u_i = x_i − x_rest,i, and form spring vectors as
//! r_ij = (x_rest,i − x_rest,j) + (u_i − u_j): mathematically identical to
//! eq. 4.4–4.7 in absolute positions, but no rounded quantity is of the
//! size of the absolute coordinates, so the f32 noise floor of the forces
//! drops from ~ε_f32·|x| to ~ε_f32·|u| (~20× on a face model with mm
//! displacements) and the very soft sliding modes of large networks
//! settle where the exact equilibrium is. Reports and
//! [`Simulation::positions`] give absolute positions.

pub mod bench;
pub mod chebyshev;
pub mod cpu;
mod cpu_stepper;
pub mod ct;
pub mod explicit;
pub mod fragments;
pub mod gpu;
mod job;
mod kdtree;
pub mod network;
pub mod oracle;
pub mod phantom;
pub mod plan;
pub mod relax;
pub mod selector;
pub mod stepper;

pub use ct::{CtLayers, CtParams, layers_from_ct};
pub use fragments::{BoneCut, CutBone, Fragments, KnifeSpec, cut_bone};
pub use job::{BoneCutFigures, Job};
pub use network::{
    Material, NetworkParams, Spring, SpringClass, SpringNetwork, Stiffness, StiffnessRegion,
    default_origin,
};
pub use plan::{Dynamics, Iterations, Plan, ResolvedPlan, Rotation, Step};
pub use relax::{
    IncrementReport, RelaxReport, Simulation, Status, StepProbe, StepReport, iterate, relax,
};
pub use selector::Selector;
pub use stepper::{RelaxOptions, Solver};
