//! GPU timing: timestamp queries around the compute passes of one command
//! encoder, when the device has `TIMESTAMP_QUERY`.
//!
//! ```text
//! let timer = gpu.pass_timer(2);                  // None without timestamps
//! pass 0: timestamp_writes: timer.as_ref().map(|t| t.writes(0))
//! pass 1: timestamp_writes: timer.as_ref().map(|t| t.writes(1))
//! let times = timer.map(|t| t.stage(gpu, &mut encoder)).transpose()?;
//! gpu.submit_and_wait(encoder)?;
//! let seconds = times.map(|t| t.finish(gpu)).transpose()?;  // per pass: end − begin
//! ```

use super::{Gpu, GpuArray, Staged};
use crate::Result;

/// Begin/end timestamp queries for `passes` compute passes.
#[derive(Debug)]
pub struct PassTimer {
    set: wgpu::QuerySet,
    passes: u32,
}

/// Resolved timestamps on their way back to the host.
#[derive(Debug)]
pub struct PassTimes {
    ticks: Staged<u64>,
}

impl Gpu {
    /// A timer for up to `passes` compute passes of one encoder, or `None`
    /// when the device has no timestamp queries (or `passes` is 0).
    pub fn pass_timer(&self, passes: u32) -> Option<PassTimer> {
        (self.features.timestamps && passes > 0).then(|| PassTimer {
            set: self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("chisel.timing"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            }),
            passes,
        })
    }
}

impl PassTimer {
    /// The timestamp writes of pass `i` (`i < passes`): its begin and end.
    pub fn writes(&self, i: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        debug_assert!(i < self.passes, "pass {i} of {}", self.passes);
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        }
    }

    /// Resolves the queries and copies them out with `encoder` (read them
    /// with [`PassTimes::finish`] after the submit).
    pub fn stage(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<PassTimes> {
        let n = 2 * self.passes;
        let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chisel.timing.resolve"),
            size: u64::from(n) * 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        encoder.resolve_query_set(&self.set, 0..n, &resolve, 0);
        let ticks = GpuArray::<u64>::from_raw(resolve, n as usize, "timing");
        Ok(PassTimes {
            ticks: ticks.stage(gpu, encoder)?,
        })
    }
}

impl PassTimes {
    /// Seconds of each timed pass on the GPU clock (end − begin), in pass
    /// order.
    pub fn finish(self, gpu: &Gpu) -> Result<Vec<f64>> {
        let t = self.ticks.finish(gpu)?;
        let period = f64::from(gpu.queue.get_timestamp_period());
        Ok(t.chunks(2)
            .map(|p| p[1].saturating_sub(p[0]) as f64 * period * 1e-9)
            .collect())
    }
}
