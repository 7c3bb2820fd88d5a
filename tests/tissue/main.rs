//! Tissue model: network construction, plans and their validation, Δt
//! policy, the f64 oracle against analytic cases, the CPU mirror against the
//! oracle, stop criteria, and the accelerated solver's equilibrium.

#[path = "../common/mod.rs"]
mod common;
mod fast_path;
mod fran_cut;
mod network;
mod oracle_cases;
mod plans;
mod solvers;

use chisel::Backend;
use chisel::mesh::TriMesh;
use chisel::tissue::network::unique_edges;
use chisel::tissue::oracle::{self, OracleState};
use chisel::tissue::phantom::{self, FRAN_GRID};
use chisel::tissue::{
    Fragments, Iterations, Material, NetworkParams, Plan, RelaxOptions, Selector, Solver,
    SpringClass, SpringNetwork, Status, Step, Stiffness, explicit, relax,
};
use glam::{DVec3, Vec3};

/// A flat `nx × ny` grid patch in the x–y plane (spacing 1), wound +z.
fn grid(nx: usize, ny: usize) -> TriMesh {
    common::grid_mesh(nx, ny, |i, j| {
        Vec3::new(i as f32, j as f32, 0.1 * ((i * j) % 3) as f32)
    })
}
