//! Timed rendering for benchmarks (`Renderer::render_timed`): a wait after every dispatch, GPU timestamps where
//! the device has them.

use super::Renderer;
use crate::gpu::timer::GpuTimer;
use crate::gpu::GpuContext;
use crate::render::error::RenderError;
use web_time::Instant;

/// What a timed render did (`Renderer::render_timed`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Sum of the render passes' GPU durations (timestamp queries); None without TIMESTAMP_QUERY.
    pub gpu: Option<f64>,
    /// Wall time of submitting and waiting (readbacks for metrics excluded).
    pub wall: f64,
    /// Rays traced.
    pub rays: u64,
}

impl Timing {
    /// GPU time where measured, else wall time.
    pub fn seconds(&self) -> f64 {
        self.gpu.unwrap_or(self.wall)
    }
}

impl Renderer {
    /// Renders `spp` more samples per pixel like `render`, but waits after every dispatch and times each with
    /// `timer` (GPU time) and the wall clock, for benchmarks.
    pub fn render_timed(
        &mut self,
        ctx: &GpuContext,
        spp: u32,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<Timing, RenderError> {
        self.prepare()?;
        let mut timing = Timing { gpu: timer.as_ref().map(|_| 0.0), ..Timing::default() };
        let rays_before = self.rays_total;
        // The guide's learning pass and the rest of sample 0 may be this call's first sample (timed like the others).
        let before = self.samples;
        if spp > 0 {
            let t0 = Instant::now();
            self.ensure_guide_timed(ctx, timer.as_deref_mut())?;
            timing.wall += t0.elapsed().as_secs_f64();
        }
        let chunk = self.max_dispatch_spp();
        let mut left = spp - (self.samples - before);
        while left > 0 {
            let n = left.min(chunk);
            let t0 = Instant::now();
            let mut enc = self.device.create_command_encoder(&Default::default());
            self.record(&mut enc, n, timer.as_deref_mut());
            self.queue.submit([enc.finish()]);
            ctx.wait()?;
            timing.wall += t0.elapsed().as_secs_f64();
            left -= n;
            let full = timer.as_ref().is_some_and(|t| t.is_full());
            if full || left == 0 {
                if let (Some(t), Some(g)) = (timer.as_deref_mut(), timing.gpu.as_mut()) {
                    *g += t.read(ctx)?.iter().sum::<f64>();
                }
                // Also bounds the device's 32-bit ray counter between readbacks.
                self.collect_counters(ctx)?;
            }
        }
        // The guide's passes, where they were all this call rendered.
        if let (Some(t), Some(g)) = (timer.as_deref_mut(), timing.gpu.as_mut()) {
            *g += t.read(ctx)?.iter().sum::<f64>();
        }
        timing.rays = self.rays_total - rays_before;
        Ok(timing)
    }
}
