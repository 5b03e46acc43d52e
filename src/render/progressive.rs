//! Driving a Renderer to a budget: a sample count or a time, in submissions sized to take about
//! `TARGET_SUBMIT_SECONDS` each (few, large dispatches suit lavapipe; short ones keep Ctrl-C and
//! progress responsive). Samples are merged one at a time on the device, so how they are split
//! into submissions never changes the image.

use crate::gpu::GpuContext;
use crate::render::Renderer;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Wall time one submission should take.
pub const TARGET_SUBMIT_SECONDS: f64 = 1.0;

/// When to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// This many samples per pixel.
    Samples(u32),
    /// Render for this long (pipelines already built), at least one sample per pixel.
    Time(Duration),
}

/// What a progressive render did.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Samples per pixel accumulated in every pixel.
    pub spp: u32,
    /// Film rows that hold one sample more (a time budget's last, partial pass: `run`).
    pub extra_rows: u32,
    /// Seconds spent rendering (submissions and waits).
    pub seconds: f64,
    /// Rays traced.
    pub rays: u64,
    /// Non-finite samples counted on the device.
    pub nonfinite: u64,
    /// Whether the render stopped early because of an interrupt.
    pub interrupted: bool,
}

/// Renders until the budget is met or `interrupt` is set. `progress(spp_done, seconds)` is called
/// after every submission.
pub fn run(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    budget: Budget,
    interrupt: &AtomicBool,
    mut progress: impl FnMut(u32, f64),
) -> Result<RenderStats, String> {
    let start = Instant::now();
    let start_samples = renderer.samples();
    let mut batch = 1u32;
    let mut interrupted = false;
    let mut extra_rows = 0;
    loop {
        let done = renderer.samples() - start_samples;
        let elapsed = start.elapsed().as_secs_f64();
        let remaining = match budget {
            Budget::Samples(n) => n.saturating_sub(done),
            Budget::Time(t) => {
                if done > 0 && elapsed >= t.as_secs_f64() {
                    0
                } else {
                    u32::MAX
                }
            }
        };
        if remaining == 0 {
            break;
        }
        if interrupt.load(Ordering::SeqCst) {
            interrupted = true;
            break;
        }
        let mut n = batch.min(remaining);
        if let Budget::Time(t) = budget {
            // Passes that fit in the time left, at the time per pass so far. Whole passes as long as one fits; then
            // one sample more in as many film rows as fit, so the render ends near its budget instead of up to a
            // whole pass before or after it (1.1 s at 640×360 in an interior on lavapipe, a fifth of a 2T budget).
            // Each pixel's mean is over its own samples, so the image stays unbiased; those rows are a little less
            // noisy.
            let per_sample = if done > 0 { elapsed / done as f64 } else { 0.0 };
            if per_sample > 0.0 {
                let passes = (t.as_secs_f64() - elapsed).max(0.0) / per_sample;
                if passes < 1.0 {
                    let rows = (passes * renderer.settings().height as f64) as u32;
                    if rows > 0 && !interrupt.load(Ordering::SeqCst) {
                        renderer.render_rows(ctx, rows)?;
                        extra_rows = rows;
                    }
                    break;
                }
                n = n.min(passes as u32);
            }
        }
        let t0 = Instant::now();
        renderer.render(ctx, n)?;
        let dt = t0.elapsed().as_secs_f64();
        progress(renderer.samples() - start_samples, start.elapsed().as_secs_f64());
        // Size the next submission from the measured time per sample.
        let per = dt / n as f64;
        batch = ((TARGET_SUBMIT_SECONDS / per.max(1e-9)) as u32).clamp(1, 4096);
    }
    Ok(RenderStats {
        spp: renderer.samples() - start_samples,
        extra_rows,
        seconds: start.elapsed().as_secs_f64(),
        rays: renderer.rays_total(),
        nonfinite: renderer.nonfinite_total(),
        interrupted,
    })
}
