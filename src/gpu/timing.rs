//! GPU timing: timestamp queries around a compute pass when the device has
//! `TIMESTAMP_QUERY`, wall clock around submit + wait otherwise.

use std::time::{Duration, Instant};

use super::Gpu;
use crate::Result;

/// How long a piece of GPU work took, and by which clock.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GpuTiming {
    /// Seconds.
    pub seconds: f64,
    /// `true`: GPU timestamps around the pass; `false`: host wall clock
    /// around submit and wait (includes submission overhead).
    pub gpu_clock: bool,
}

impl Gpu {
    /// Records one compute pass with `record`, submits it and waits; returns
    /// the time the pass took on the GPU clock when available.
    pub fn timed_pass(
        &self,
        label: &str,
        record: impl FnOnce(&mut wgpu::ComputePass<'_>),
    ) -> Result<GpuTiming> {
        let mut encoder = self.encoder(label);
        let query = self.features.timestamps.then(|| {
            let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("chisel.timing"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("chisel.timing.resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&format!("chisel.{label}")),
                timestamp_writes: query
                    .as_ref()
                    .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }),
            });
            record(&mut pass);
        }
        let start = Instant::now();
        match query {
            Some((set, resolve)) => {
                encoder.resolve_query_set(&set, 0..2, &resolve, 0);
                let ticks = super::GpuArray::<u64>::from_raw(resolve, 2, "timing");
                let staged = ticks.stage(self, &mut encoder)?;
                self.submit_and_wait(encoder)?;
                let t = staged.finish(self)?;
                let period = f64::from(self.queue.get_timestamp_period());
                let ns = t[1].saturating_sub(t[0]) as f64 * period;
                Ok(GpuTiming {
                    seconds: ns * 1e-9,
                    gpu_clock: true,
                })
            }
            None => {
                self.submit_and_wait(encoder)?;
                Ok(GpuTiming {
                    seconds: Duration::as_secs_f64(&start.elapsed()),
                    gpu_clock: false,
                })
            }
        }
    }
}
