//! GPU time of compute passes from timestamp queries: the one timer the renderer, the benchmarks and the viewer
//! share. `pass()` hands out the timestamp writes of the next pass; `read()` resolves them and returns the seconds
//! each pass took, in the order they were handed out, and starts over.

use crate::gpu::{GpuContext, GpuError};

/// Timestamp queries for up to `capacity` passes between two reads.
pub struct GpuTimer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    capacity: u32,
    used: u32,
    period_ns: f64,
}

impl GpuTimer {
    /// A timer for `capacity` passes, or None where the device has no timestamp queries in compute passes.
    pub fn new(ctx: &GpuContext, capacity: u32) -> Option<GpuTimer> {
        if !ctx.timestamps {
            return None;
        }
        let capacity = capacity.max(1);
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * capacity,
        });
        let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass timestamps"),
            size: 16 * capacity as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(GpuTimer { set, resolve, capacity, used: 0, period_ns: ctx.queue.get_timestamp_period() as f64 })
    }

    /// Whether every pass slot is taken (call `read` before timing more).
    pub fn is_full(&self) -> bool {
        self.used == self.capacity
    }

    /// The timestamp writes of the next pass; None when full (that pass then goes untimed).
    pub fn pass(&mut self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        if self.is_full() {
            return None;
        }
        let k = self.used;
        self.used += 1;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    /// Seconds of each pass timed since the last read, in order; waits for them (submit the passes first).
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<f64>, GpuError> {
        let n = self.used;
        self.used = 0;
        if n == 0 {
            return Ok(Vec::new());
        }
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.resolve_query_set(&self.set, 0..2 * n, &self.resolve, 0);
        ctx.queue.submit([enc.finish()]);
        let t: Vec<u64> = ctx.read_pod(&self.resolve, 2 * n as usize)?;
        Ok((0..n as usize).map(|k| t[2 * k + 1].saturating_sub(t[2 * k]) as f64 * self.period_ns * 1e-9).collect())
    }
}
