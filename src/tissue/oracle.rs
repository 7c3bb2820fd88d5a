//! f64 textbook oracle of the tissue dynamics (eq. 4.4–4.7), independent of
//! the CSR, the packing and the f32 mirror: springs are visited once each
//! from the spring list and their forces *scattered* to both ends, and the
//! biphasic law is written piecewise as in the seed's Fig. 3.2.
//!
//! Checked against analytic cases in the tests (a single damped spring's
//! period and decay, a chain's static equilibrium, the biphasic knee).

use glam::DVec3;

use super::network::{Material, SpringNetwork};

/// Force magnitude of `m` at extension `e` for rest length `l`:
/// `c1·e` up to `e = knee·l`, then `c2` on the rest (continuous).
pub fn spring_force(m: &Material, e: f64, l: f64) -> f64 {
    let (c1, c2, knee) = (m.c1 as f64, m.c2 as f64, m.knee as f64);
    let e_knee = knee * l;
    if e <= e_knee {
        c1 * e
    } else {
        c1 * e_knee + c2 * (e - e_knee)
    }
}

/// g_i of eq. 4.4 for every node (fixed nodes included), by scatter over
/// the spring list.
pub fn spring_forces(net: &SpringNetwork, x: &[DVec3]) -> Vec<DVec3> {
    let mut g = vec![DVec3::ZERO; x.len()];
    for s in &net.springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let r = x[a] - x[b];
        let len = r.length();
        if len == 0.0 {
            continue;
        }
        let f = spring_force(
            &net.materials[s.material as usize],
            len - s.rest as f64,
            s.rest as f64,
        );
        let fr = r * (f / len);
        g[a] += fr;
        g[b] -= fr;
    }
    g
}

/// Node positions and velocities in f64.
#[derive(Debug, Clone, PartialEq)]
pub struct OracleState {
    pub x: Vec<DVec3>,
    pub v: Vec<DVec3>,
}

impl OracleState {
    /// The rest state with the bone layer at `bone` (#bone).
    pub fn new(net: &SpringNetwork, bone: &[DVec3]) -> Self {
        let mut x: Vec<DVec3> = net
            .rest
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        x[net.n_free..].copy_from_slice(bone);
        OracleState {
            v: vec![DVec3::ZERO; x.len()],
            x,
        }
    }

    /// One semi-implicit Euler step with external forces `f` (#free or
    /// empty = 0): a = (f − γv − g)·B/m, v += Δt a, x += Δt v; fixed nodes
    /// have B = 0.
    #[expect(
        clippy::needless_range_loop,
        reason = "x, v, g and f are indexed by node id alike"
    )]
    pub fn step(&mut self, net: &SpringNetwork, dt: f64, f: &[DVec3]) {
        let g = spring_forces(net, &self.x);
        let (m, gamma) = (net.params.mass as f64, net.params.damping as f64);
        for i in 0..net.n_free {
            let fi = f.get(i).copied().unwrap_or(DVec3::ZERO);
            let a = (fi - gamma * self.v[i] - g[i]) / m;
            self.v[i] += dt * a;
            self.x[i] += dt * self.v[i];
        }
    }

    /// max_i |v_i| over the free nodes.
    pub fn max_speed(&self, net: &SpringNetwork) -> f64 {
        self.v[..net.n_free]
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max)
    }

    /// max_i |f_i − g_i| over the free nodes: the static residual.
    pub fn residual(&self, net: &SpringNetwork, f: &[DVec3]) -> f64 {
        let g = spring_forces(net, &self.x);
        (0..net.n_free)
            .map(|i| (f.get(i).copied().unwrap_or(DVec3::ZERO) - g[i]).length())
            .fold(0.0, f64::max)
    }

    /// Steps until max |v| < `eps` (checked every step) or `max_steps`;
    /// returns the number of steps taken.
    pub fn settle(
        &mut self,
        net: &SpringNetwork,
        dt: f64,
        f: &[DVec3],
        eps: f64,
        max_steps: usize,
    ) -> usize {
        for k in 1..=max_steps {
            self.step(net, dt, f);
            if self.max_speed(net) < eps {
                return k;
            }
        }
        max_steps
    }
}
