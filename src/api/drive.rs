//! The one loop that drives a renderer to a budget: a sample count or a time, in submissions sized to take about
//! `TARGET_SUBMIT_SECONDS` each (few, large dispatches suit lavapipe; short ones keep interrupts and progress
//! responsive), with checkpoints when due. Samples are merged one at a time on the device, so how they are split
//! into submissions never changes the image.

use super::budget::{Budget, RenderStats};
use super::error::ApiError;
use super::observer::{Observer, Progress};
use crate::gpu::GpuContext;
use crate::render::Renderer;
use std::time::Duration;
use web_time::Instant;

/// Wall time one submission should take.
pub const TARGET_SUBMIT_SECONDS: f64 = 1.0;

/// Writes a checkpoint of the renderer (`state::session::Session::save`), given this run's seconds so far.
pub type SaveCheckpoint<'a> = &'a mut dyn FnMut(&Renderer, f64) -> Result<(), ApiError>;

/// How to drive: the budget, the submission length, and checkpoints.
pub struct Plan<'a> {
    /// When to stop.
    pub budget: Budget,
    /// Wall time one submission should take (an observer is asked between submissions).
    pub submit_seconds: f64,
    /// Checkpoint every so often while the render is not finished (submissions are no longer than the interval).
    pub checkpoint: Option<(Duration, SaveCheckpoint<'a>)>,
}

impl Plan<'_> {
    /// A plan with the default submission length and no checkpoints.
    pub fn of(budget: Budget) -> Plan<'static> {
        Plan { budget, submit_seconds: TARGET_SUBMIT_SECONDS, checkpoint: None }
    }
}

/// Renders until the budget is met or the observer asks to stop; returns what this run did.
pub fn drive(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    mut plan: Plan<'_>,
    observer: &mut dyn Observer,
) -> Result<RenderStats, ApiError> {
    let start = Instant::now();
    let (first, rays_first) = (renderer.samples(), renderer.rays_total());
    let target = match &plan.checkpoint {
        Some((every, _)) => every.as_secs_f64().min(plan.submit_seconds),
        None => plan.submit_seconds,
    };
    let mut last_checkpoint = Instant::now();
    let mut batch = 1u32;
    let mut interrupted = false;
    let mut extra_rows = 0;
    loop {
        let done = renderer.samples() - first;
        let elapsed = start.elapsed().as_secs_f64();
        let remaining = match plan.budget {
            Budget::Samples(n) => n.saturating_sub(done),
            Budget::Time(t) if done > 0 && elapsed >= t.as_secs_f64() => 0,
            Budget::Time(_) => u32::MAX,
        };
        if remaining == 0 {
            break;
        }
        if observer.stop_requested() {
            interrupted = true;
            break;
        }
        let mut n = batch.min(remaining);
        if let Budget::Time(t) = plan.budget {
            // Passes that fit in the time left, at the time per pass so far. Whole passes as long as one fits; then
            // one sample more in as many film rows as fit, so the render ends near its budget instead of up to a
            // whole pass before or after it. Each pixel's mean is over its own samples, so the image stays
            // unbiased; those rows are a little less noisy.
            let per_sample = if done > 0 { elapsed / done as f64 } else { 0.0 };
            if per_sample > 0.0 {
                let passes = (t.as_secs_f64() - elapsed).max(0.0) / per_sample;
                if passes < 1.0 {
                    let rows = (passes * renderer.settings().height as f64) as u32;
                    if rows > 0 && !observer.stop_requested() {
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
        observer.progress(&Progress {
            spp: renderer.samples() - first,
            sample_index: renderer.samples(),
            seconds: start.elapsed().as_secs_f64(),
            rays: renderer.rays_total() - rays_first,
            nonfinite: renderer.nonfinite_total(),
        });
        let finished = matches!(plan.budget, Budget::Samples(total) if renderer.samples() - first >= total);
        if let Some((every, save)) = plan.checkpoint.as_mut() {
            if !finished && last_checkpoint.elapsed() >= *every {
                save(renderer, start.elapsed().as_secs_f64())?;
                last_checkpoint = Instant::now();
            }
        }
        // Size the next submission from the measured time per sample.
        batch = ((target / (dt / n as f64).max(1e-9)) as u32).clamp(1, 4096);
    }
    Ok(RenderStats {
        spp: renderer.samples() - first,
        extra_rows,
        seconds: start.elapsed().as_secs_f64(),
        rays: renderer.rays_total() - rays_first,
        nonfinite: renderer.nonfinite_total(),
        interrupted,
    })
}
