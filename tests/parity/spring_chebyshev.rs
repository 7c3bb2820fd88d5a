//! Parity of `kernels/spring_chebyshev.wgsl` with
//! `tissue::cpu::spring_chebyshev` (accelerated solver), with the fixtures,
//! tolerance, negative control and sentinel checks of `spring_step.rs`.

use chisel::tissue::Solver;

use super::spring_step::{check_iterations, check_single_step, check_stop_status};
use crate::common;

#[test]
fn spring_chebyshev_single_dispatch() {
    let Some(gpu) = common::gpu() else { return };
    check_single_step(gpu, Solver::Chebyshev);
}

#[test]
fn spring_chebyshev_after_n_iterations() {
    let Some(gpu) = common::gpu() else { return };
    check_iterations(gpu, Solver::Chebyshev, 201);
}

#[test]
fn spring_chebyshev_stop_status() {
    let Some(gpu) = common::gpu() else { return };
    check_stop_status(gpu, Solver::Chebyshev);
}
