//! The step kernels' fast path against their mirrors, bit for bit, on
//! synthetic networks and on fran_cut.

use super::*;

/// The step kernels' fast path equals their mirrors (the plain per-node
/// loops) bit for bit at every gather width this CPU has (detected at run
/// time: 4 everywhere, 8 with AVX2, 16 with AVX-512), for free
/// node counts that fill no whole lane group, rows of 0 to many springs
/// (lanes ending at different k, inside and past the interleaved steps of
/// a wide group), a zero-length spring, three materials (one of them id
/// 15, the last of the table) and external forces.
#[test]
fn fast_path_equals_the_mirror() {
    use chisel::tissue::cpu::fast::{Lanes, SpringGather};
    use chisel::tissue::cpu::{self, SpringChebyshevParams, SpringStepParams};
    let widths: Vec<Lanes> = Lanes::ALL
        .into_iter()
        .filter(|l| l.is_available())
        .collect();
    for l in Lanes::ALL.into_iter().filter(|l| !l.is_available()) {
        eprintln!("this CPU lacks {}: not tested here", l.name());
    }
    let mut bits = common::xorshift(0x2545_f491_4f6c_dd1d);
    let mut next = move || (bits() >> 40) as f32 / (1u64 << 24) as f32;
    let mut materials = vec![Material::linear(0.1); 16];
    materials[0] = Material::linear(1.3);
    materials[1] = Material {
        c1: 0.7,
        c2: 4.0,
        knee: 0.05,
    };
    materials[15] = Material {
        c1: 2.0,
        c2: 0.5,
        knee: 0.02,
    };
    let mut mats = [[0.0f32; 4]; 16];
    for (row, m) in mats.iter_mut().zip(&materials) {
        *row = m.table_row();
    }
    for n_free in [1usize, 2, 3, 5, 6, 7, 9, 13, 16, 17, 24, 31, 40, 53, 70] {
        let n = n_free + 4;
        let mut p: Vec<Vec3> = (0..n).map(|_| Vec3::new(next(), next(), next())).collect();
        // Nodes 0 and 1 coincide: a spring of rest length 0.
        p[1] = p[0];
        let mut springs = vec![(0u32, 1u32, 0u8)];
        for a in 0..n as u32 {
            // Rows of 0 to 4 own springs (plus those of other nodes), and
            // beyond 16 nodes 6 to 9 more (every lane of a wide group has
            // springs, its rows end at different k).
            let own = if n_free > 16 {
                6 + a as usize % 4
            } else {
                a as usize % 5
            };
            for k in 0..own {
                let b = (a as usize + 1 + 2 * k) % n;
                springs.push((a, b as u32, [0, 1, 15][k % 3]));
            }
        }
        springs.retain(|&(a, b, _)| a != b);
        let net = SpringNetwork::from_parts(&p, n_free, &springs, &materials, 1.0, 0.5).unwrap();
        let mut pos: Vec<[f32; 4]> = (0..n)
            .map(|i| {
                let w = if i < n_free { 0.5 + next() } else { 0.0 };
                [
                    0.2 * next() - 0.1,
                    0.2 * next() - 0.1,
                    0.2 * next() - 0.1,
                    w,
                ]
            })
            .collect();
        // ... and keep coinciding: r = 0, which the kernels skip.
        let first = pos[0];
        pos[1][..3].copy_from_slice(&first[..3]);
        let vel: Vec<[f32; 4]> = (0..n_free)
            .map(|_| [next() - 0.5, next() - 0.5, 0.0, 0.0])
            .collect();
        let forces: Vec<[f32; 4]> = (0..n_free)
            .map(|_| [next() - 0.5, 0.0, next(), 0.0])
            .collect();
        for (chebyshev, &lanes) in [false, true]
            .into_iter()
            .flat_map(|c| widths.iter().map(move |l| (c, l)))
        {
            // The parameters of both kernels (their fields by name).
            struct Params {
                dt: f32,
                damping: f32,
                gain: f32,
                isotropy: f32,
            }
            let params = Params {
                dt: 0.05,
                damping: if chebyshev { 0.9 } else { 0.5 },
                gain: 1.7,
                isotropy: 0.1,
            };
            let chebyshev_params = SpringChebyshevParams {
                n_free: n_free as u32,
                use_forces: true,
                h: params.dt,
                momentum: params.damping,
                gain: params.gain,
                isotropy: params.isotropy,
                materials: mats,
            };
            let step_params = SpringStepParams {
                n_free: n_free as u32,
                use_forces: true,
                dt: params.dt,
                damping: params.damping,
                materials: mats,
            };
            // Fast path and mirror from the same inputs; `forces` and
            // `vel` zero: the springs alone (their loading).
            let run = |fast: bool, forces: &[[f32; 4]], vel: &[[f32; 4]]| {
                let (mut out, mut v_out) = (pos.clone(), vel.to_vec());
                let gather = SpringGather::new(&net.csr, n_free, lanes).unwrap();
                assert_eq!(gather.lanes(), lanes);
                let (rest, csr) = (&net.rest, &net.csr);
                match (chebyshev, fast) {
                    (true, true) => gather.spring_chebyshev(
                        &chebyshev_params,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                    (true, false) => cpu::spring_chebyshev(
                        &chebyshev_params,
                        csr,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                    (false, true) => {
                        gather.spring_step(&step_params, rest, forces, &pos, &mut out, &mut v_out)
                    }
                    (false, false) => cpu::spring_step(
                        &step_params,
                        csr,
                        rest,
                        forces,
                        &pos,
                        &mut out,
                        &mut v_out,
                    ),
                }
                (out, v_out)
            };
            let (out, v_out) = run(true, &forces, &vel);
            let (m_out, m_vel) = run(false, &forces, &vel);
            for i in 0..n {
                let what = format!(
                    "{}: n_free {n_free}, chebyshev {chebyshev}, node {i}",
                    lanes.name()
                );
                assert_eq!(
                    out[i].map(f32::to_bits),
                    m_out[i].map(f32::to_bits),
                    "position: {what}"
                );
                if i < n_free {
                    assert_eq!(
                        v_out[i].map(f32::to_bits),
                        m_vel[i].map(f32::to_bits),
                        "velocity: {what}"
                    );
                }
            }
            let zero = vec![[0.0f32; 4]; n_free];
            let loaded = run(false, &zero, &zero)
                .1
                .iter()
                .any(|v| v[..3] != [0.0; 3]);
            assert!(loaded, "the springs must be loaded");
            // Only the free nodes are written.
            assert_eq!(&out[n_free..], &pos[n_free..]);
        }
    }
}

/// On fran_cut's network (real data) with the bone advanced 2 mm, every
/// gather width this CPU has gives the mirror's bits through 30 iterations
/// of each solver (the interleaved rows of 8 and 16 nodes, the tails past
/// them and the four-lane rest of each rayon task all take part).
#[test]
fn fast_path_equals_the_mirror_on_fran_cut() {
    use chisel::tissue::chebyshev::BLOCK_ISOTROPY;
    use chisel::tissue::cpu::fast::{Lanes, SpringGather};
    use chisel::tissue::cpu::{self, SpringChebyshevParams, SpringStepParams};
    let Some(face) = common::real_mesh("fran_cut.vtk") else {
        return;
    };
    let net = SpringNetwork::build(&face, None, &NetworkParams::default()).unwrap();
    let nf = net.n_free;
    let mut mats = [[0.0f32; 4]; 16];
    for (row, m) in mats.iter_mut().zip(&net.materials) {
        *row = m.table_row();
    }
    let mut start = vec![[0.0f32, 0.0, 0.0, 1.0 / net.params.mass]; net.n_nodes()];
    for u in &mut start[nf..] {
        *u = [0.0, 0.002, 0.001, 0.0];
    }
    let widths: Vec<Lanes> = Lanes::ALL
        .into_iter()
        .filter(|l| l.is_available())
        .collect();
    let dt = explicit::choose_dt(&net, None, false).unwrap();
    let step = SpringStepParams {
        n_free: nf as u32,
        use_forces: false,
        dt,
        damping: net.params.damping,
        materials: mats,
    };
    let chebyshev_params = SpringChebyshevParams {
        n_free: nf as u32,
        use_forces: false,
        h: dt,
        momentum: 0.9,
        gain: 0.5,
        isotropy: BLOCK_ISOTROPY,
        materials: mats,
    };
    for chebyshev in [false, true] {
        let states: Vec<_> = widths
            .iter()
            .map(|&lanes| {
                let gather = SpringGather::new(&net.csr, nf, lanes).unwrap();
                let (mut a, mut b) = (start.clone(), start.clone());
                let mut vel = vec![[0.0f32; 4]; nf];
                for _ in 0..30 {
                    if chebyshev {
                        gather.spring_chebyshev(
                            &chebyshev_params,
                            &net.rest,
                            &[],
                            &a,
                            &mut b,
                            &mut vel,
                        );
                    } else {
                        gather.spring_step(&step, &net.rest, &[], &a, &mut b, &mut vel);
                    }
                    std::mem::swap(&mut a, &mut b);
                }
                (a, vel)
            })
            .collect();
        let mirror = {
            let (mut a, mut b) = (start.clone(), start.clone());
            let mut vel = vec![[0.0f32; 4]; nf];
            for _ in 0..30 {
                if chebyshev {
                    let p = &chebyshev_params;
                    cpu::spring_chebyshev(p, &net.csr, &net.rest, &[], &a, &mut b, &mut vel);
                } else {
                    cpu::spring_step(&step, &net.csr, &net.rest, &[], &a, &mut b, &mut vel);
                }
                std::mem::swap(&mut a, &mut b);
            }
            (a, vel)
        };
        let moved = states[0].0[..nf]
            .iter()
            .filter(|u| u[..3] != [0.0; 3])
            .count();
        assert!(
            moved > nf / 4,
            "the bone move must load the network: {moved} of {nf} moved"
        );
        for (lanes, (u, v)) in widths.iter().zip(&states) {
            let bits = |x: &[[f32; 4]]| x.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(u) == bits(&mirror.0) && bits(v) == bits(&mirror.1),
                "{} differs from the mirror (chebyshev {chebyshev})",
                lanes.name(),
            );
        }
    }
}
