//! The CPU as a [`Stepper`]: the state in host memory, the step kernels'
//! fast path ([`SpringGather`], equal to the mirrors bit for bit) arranged
//! once per network, the convergence probe by
//! [`cpu::tissue_reduce_max`].

use super::cpu;
use super::cpu::fast::SpringGather;
use super::network::SpringNetwork;
use super::stepper::{Probe, Setup, StepKernel, Stepper, absolute, bone_displacements};
use crate::Result;

/// The CPU mirror as a [`Stepper`].
#[derive(Debug)]
pub(crate) struct CpuStepper<'a> {
    net: &'a SpringNetwork,
    gather: SpringGather<'a>,
    setup: Setup,
    pos: [Vec<[f32; 4]>; 2],
    cur: usize,
    vel: Vec<[f32; 4]>,
    snap: Vec<[f32; 4]>,
}

impl<'a> CpuStepper<'a> {
    pub fn new(net: &'a SpringNetwork, setup: Setup) -> Self {
        let pos = [setup.positions.clone(), setup.positions.clone()];
        CpuStepper {
            net,
            gather: SpringGather::best(&net.csr, net.n_free),
            vel: vec![[0.0; 4]; net.n_free],
            snap: setup.positions[..net.n_free].to_vec(),
            setup,
            pos,
            cur: 0,
        }
    }

    /// One iteration of the solver's mirror.
    pub fn iterate(&mut self) {
        let (a, b) = self.pos.split_at_mut(1);
        let (src, dst) = if self.cur == 0 {
            (&a[0], &mut b[0])
        } else {
            (&b[0], &mut a[0])
        };
        let (rest, forces) = (&self.net.rest, &self.setup.forces);
        match &self.setup.kernel {
            StepKernel::SpringStep(p) => {
                (self.gather).spring_step(p, rest, forces, src, dst, &mut self.vel);
            }
            StepKernel::SpringChebyshev(p) => {
                (self.gather).spring_chebyshev(p, rest, forces, src, dst, &mut self.vel);
            }
        }
        self.cur ^= 1;
    }
}

impl Stepper for CpuStepper<'_> {
    fn set_bone(&mut self, bone: &[[f32; 4]]) -> Result<()> {
        let u = bone_displacements(self.net.bone_rest(), bone)?;
        let nf = self.net.n_free;
        for buf in &mut self.pos {
            buf[nf..].copy_from_slice(&u);
        }
        Ok(())
    }

    fn reset_velocities(&mut self) -> Result<()> {
        self.vel.fill([0.0; 4]);
        Ok(())
    }

    fn snapshot(&mut self) -> Result<()> {
        let nf = self.net.n_free;
        self.snap.copy_from_slice(&self.pos[self.cur][..nf]);
        Ok(())
    }

    fn advance(&mut self, n: u32, window: bool) -> Result<Probe> {
        // Iterate on a pool thread: each iteration's parallel loop is then
        // shared by work stealing among awake threads instead of waking the
        // pool and putting this thread to sleep once per iteration.
        rayon::scope(|_| {
            for _ in 0..n {
                self.iterate();
            }
        });
        let nf = self.net.n_free;
        let keys = cpu::tissue_reduce_max(nf, &self.vel, &self.pos[self.cur], &self.snap);
        if window {
            self.snapshot()?;
        }
        Ok(Probe { keys })
    }

    fn positions(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(absolute(&self.net.rest, &self.pos[self.cur]))
    }
}
