//! The faithful explicit solver (SPEC §1.2, seed eq. 4.4–4.7): damped
//! semi-implicit Euler on the Lagrange equations of motion.
//!
//! Stability: for a mode of stiffness λ (eigenvalue of M⁻¹K) the update
//! `v ← v + Δt(−γ' v − λ x)`, `x ← x + Δt v` (γ' = γ/m) is stable iff
//! `Δt² λ + 2 Δt γ' < 4` and `Δt γ' < 2` (Schur–Cohn on its characteristic
//! polynomial). Gershgorin bounds λ ≤ Λ = max_i 2 Σ_j c_max,ij / m_i, which
//! gives the limit below (a sufficient condition, so slightly conservative).

use super::network::SpringNetwork;
use crate::{Error, Refusal, Result};

/// Fraction of the stability limit used when the caller gives no Δt.
pub const DEFAULT_FRACTION: f32 = 0.9;

/// The explicit Δt limit of `network` (see the module docs).
pub fn stability_limit(network: &SpringNetwork) -> f32 {
    let m = network.params.mass as f64;
    let gamma = network.params.damping as f64 / m;
    let s_max = network
        .nodal_stiffness()
        .iter()
        .fold(0.0f64, |a, &s| a.max(s as f64));
    let lambda = 2.0 * s_max / m;
    let damping_limit = if gamma > 0.0 {
        2.0 / gamma
    } else {
        f64::INFINITY
    };
    let spring_limit = if lambda > 0.0 {
        (-gamma + (gamma * gamma + 4.0 * lambda).sqrt()) / lambda
    } else {
        f64::INFINITY
    };
    spring_limit.min(damping_limit).min(f32::MAX as f64) as f32
}

/// Δt to use: `requested` if it is stable (or `force`d), else an error that
/// explains the limit; `None` → [`DEFAULT_FRACTION`] of the limit.
pub fn choose_dt(network: &SpringNetwork, requested: Option<f32>, force: bool) -> Result<f32> {
    let limit = stability_limit(network);
    match requested {
        None => {
            if limit.is_finite() {
                Ok(DEFAULT_FRACTION * limit)
            } else {
                Err(Refusal::NoStableStep.into())
            }
        }
        Some(dt) if !(dt.is_finite() && dt > 0.0) => {
            Err(Error::param("dt", dt, "must be finite and > 0"))
        }
        Some(dt) if dt >= limit && !force => Err(Error::param(
            "dt",
            dt,
            format!(
                "at or above the explicit stability limit {limit:.6} \
                 (Δt²Λ + 2Δtγ/m < 4 with Λ = 2·max Σc/m from the stiffest node, m = {}, γ = {}); \
                 the integration would blow up. Use Δt < {limit:.6} (default {:.6}) or force it",
                network.params.mass,
                network.params.damping,
                DEFAULT_FRACTION * limit
            ),
        )),
        Some(dt) => Ok(dt),
    }
}
