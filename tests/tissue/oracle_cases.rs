//! The f64 oracle against analytic cases (single spring, chain, biphasic
//! knee), the f32 mirror against the oracle, and the block preconditioner.

use super::*;

/// One free node on a spring to a fixed node: a damped oscillator.
fn single_spring(c: f32, gamma: f32) -> SpringNetwork {
    SpringNetwork::from_parts(
        &[Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[Material::linear(c)],
        1.0,
        gamma,
    )
    .unwrap()
}

#[test]
fn oracle_single_spring_period_and_decay() {
    let (c, gamma) = (4.0f64, 0.2f64);
    let net = single_spring(c as f32, gamma as f32);
    let mut s = OracleState::new(&net, &[DVec3::ZERO]);
    s.x[0].x = 1.1; // 0.1 extension
    let dt = 1e-4;
    let mut crossings = Vec::new();
    let mut peaks = Vec::new();
    let mut prev = s.x[0].x - 1.0;
    let mut prev_v = 0.0;
    for k in 0..200_000 {
        s.step(&net, dt, &[]);
        let u = s.x[0].x - 1.0;
        if prev > 0.0 && u <= 0.0 {
            crossings.push(k as f64 * dt);
        }
        if prev_v > 0.0 && s.v[0].x <= 0.0 {
            peaks.push(u);
        }
        prev = u;
        prev_v = s.v[0].x;
    }
    let omega_d = (c - gamma * gamma / 4.0).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega_d;
    let measured = (crossings[5] - crossings[1]) / 4.0;
    assert!(
        (measured - period).abs() < 1e-3 * period,
        "{measured} vs {period}"
    );
    let decay = peaks[2] / peaks[1];
    let expect = (-gamma / 2.0 * period).exp();
    assert!((decay - expect).abs() < 2e-3, "{decay} vs {expect}");
}

#[test]
fn oracle_chain_reaches_series_spring_equilibrium() {
    // Fixed ends at x = 0 and x = 4 (moved to 5); three free nodes; springs
    // c = 1, 2, 1, 2 in series: equal tension, extension_i = T / c_i.
    let pos: Vec<Vec3> = [1.0, 2.0, 3.0, 0.0, 4.0]
        .iter()
        .map(|&x| Vec3::new(x, 0.0, 0.0))
        .collect();
    let mats = [Material::linear(1.0), Material::linear(2.0)];
    let net = SpringNetwork::from_parts(
        &pos,
        3,
        &[(3, 0, 0), (0, 1, 1), (1, 2, 0), (2, 4, 1)],
        &mats,
        1.0,
        1.0,
    )
    .unwrap();
    let mut s = OracleState::new(&net, &[DVec3::ZERO, DVec3::new(5.0, 0.0, 0.0)]);
    s.settle(&net, 0.1, &[], 1e-12, 1_000_000);
    let tension = 1.0 / (1.0 + 0.5 + 1.0 + 0.5);
    let expect = [1.0 + tension, 2.0 + tension * 1.5, 3.0 + tension * 2.5];
    for (k, (x, want)) in s.x.iter().zip(expect).enumerate() {
        assert!((x.x - want).abs() < 1e-9, "{k}: {} vs {want}", x.x);
    }
    assert!(s.residual(&net, &[]) < 1e-10);
}

#[test]
fn oracle_biphasic_knee() {
    let m = Material {
        c1: 1.0,
        c2: 5.0,
        knee: 0.1,
    };
    assert_eq!(oracle::spring_force(&m, 0.05, 1.0), 0.05);
    assert!((oracle::spring_force(&m, 0.2, 1.0) - (0.1 + 0.5)).abs() < 1e-7);
    // Continuous at the knee, linear in compression.
    assert!((oracle::spring_force(&m, 0.1 + 1e-12, 1.0) - 0.1).abs() < 1e-10);
    assert_eq!(oracle::spring_force(&m, -0.3, 1.0), -0.3);
    // Static load past the knee: extension = knee·l + (f − c1·knee·l)/c2.
    let net = SpringNetwork::from_parts(
        &[Vec3::new(2.0, 0.0, 0.0), Vec3::ZERO],
        1,
        &[(0, 1, 0)],
        &[m],
        1.0,
        1.0,
    )
    .unwrap();
    let f = [DVec3::new(1.2, 0.0, 0.0)];
    let mut s = OracleState::new(&net, &[DVec3::ZERO]);
    s.settle(&net, 0.05, &f, 1e-13, 1_000_000);
    let expect = 2.0 + 0.2 + (1.2 - 0.2) / 5.0;
    assert!((s.x[0].x - expect).abs() < 1e-7, "{}", s.x[0].x);
}

/// The f32 mirror tracks the f64 oracle on a biphasic network with an
/// external load (so the knee is crossed) and a moved bone.
#[test]
fn mirror_tracks_oracle() {
    let mesh = common::icosphere(2);
    let net = SpringNetwork::build(&mesh, None, &NetworkParams::default()).unwrap();
    let n = mesh.n_vertices();
    let mut bone: Vec<[f32; 4]> = net.bone_rest().to_vec();
    for b in bone.iter_mut().filter(|b| b[1] > 0.4) {
        b[2] += 0.08;
    }
    let forces: Vec<Vec3> = (0..net.n_free)
        .map(|i| {
            if i < n && mesh.positions[i].x > 0.5 {
                Vec3::new(0.3, 0.0, 0.0)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let opts = RelaxOptions {
        external_forces: Some(forces.clone()),
        ..RelaxOptions::default()
    };
    let dt = explicit::choose_dt(&net, None, false).unwrap();
    let iters = 300;
    let mirror = chisel::tissue::iterate(&net, &bone, &opts, iters, Backend::Cpu).unwrap();
    let bone64: Vec<DVec3> = bone
        .iter()
        .map(|b| DVec3::new(b[0] as f64, b[1] as f64, b[2] as f64))
        .collect();
    let f64s: Vec<DVec3> = forces.iter().map(|f| f.as_dvec3()).collect();
    let mut s = OracleState::new(&net, &bone64);
    for _ in 0..iters {
        s.step(&net, dt as f64, &f64s);
    }
    let moved = (0..net.n_free)
        .map(|i| {
            s.x[i].distance(DVec3::new(
                net.rest[i][0] as f64,
                net.rest[i][1] as f64,
                net.rest[i][2] as f64,
            ))
        })
        .fold(0.0, f64::max);
    assert!(moved > 0.05, "the test must move the network ({moved})");
    let worst = (0..net.n_free)
        .map(|i| {
            let m = mirror[i];
            s.x[i].distance(DVec3::new(m[0] as f64, m[1] as f64, m[2] as f64))
        })
        .fold(0.0, f64::max);
    // f32 rounding over 300 iterations of a unit-size network.
    assert!(worst < 1e-4, "mirror vs oracle: {worst}");
    // The dermis knee was crossed somewhere (biphasic law exercised).
    let stretched = net.springs.iter().any(|sp| {
        sp.class == SpringClass::Dermis
            && s.x[sp.a as usize].distance(s.x[sp.b as usize]) > 1.1 * sp.rest as f64
    });
    assert!(stretched);
}

/// `block_solve` inverts the 3 × 3 block: B⁻¹(B x) = x to f32 accuracy for
/// SPD blocks of condition up to ~10³ and any scale (1e-6 to 1e6), and a
/// block of zero trace (a node without springs) gives 0.
#[test]
fn block_solve_inverts_the_preconditioner_block() {
    use chisel::tissue::cpu::block_solve;
    let mut bits = common::xorshift(0x9e37_79b9_7f4a_7c15);
    let mut next = move || (bits() >> 40) as f64 / (1u64 << 24) as f64 - 0.5;
    for case in 0..200 {
        let scale = 10f64.powi(case % 13 - 6);
        // B = Σ_k λ_k e_k e_kᵀ over a random orthonormal frame.
        let a = glam::DVec3::new(next(), next(), next()).normalize();
        let b = a
            .cross(glam::DVec3::new(next(), next(), next()))
            .normalize();
        let c = a.cross(b);
        let lambda = [1.0, 10f64.powf(-3.0 * (next() + 0.5)), 0.05 + next().abs()];
        let m = glam::DMat3::from_cols(a, b, c)
            * glam::DMat3::from_diagonal(glam::DVec3::from_array(lambda) * scale)
            * glam::DMat3::from_cols(a, b, c).transpose();
        let blk = [
            m.x_axis.x, m.y_axis.y, m.z_axis.z, m.y_axis.x, m.z_axis.x, m.z_axis.y,
        ]
        .map(|v| v as f32);
        let x = glam::DVec3::new(next(), next(), next());
        let d = m * x;
        let got = block_solve(blk, [d.x as f32, d.y as f32, d.z as f32]);
        let err = (glam::DVec3::new(got[0] as f64, got[1] as f64, got[2] as f64) - x).length();
        // f32 rounding of B and d, amplified by the condition number.
        let cond = 1.0 / lambda[1].min(lambda[2]);
        assert!(
            err < 1e-5 * cond * x.length(),
            "case {case}: {err} (cond {cond})"
        );
    }
    assert_eq!(block_solve([0.0; 6], [1.0, 2.0, 3.0]), [0.0; 3]);
}
