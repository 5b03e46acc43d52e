//! One engine frame: a bounded dispatch per active side, the display pass, the readback, and the
//! book-keeping after it (GPU timestamps per dispatch, cost estimates, the frame and statistics for the UI).

use super::{Engine, Frame, PipelineState, SideStats, FRAME_BUDGET_S, MAX_SPP, PREVIEW_SCALE, STATS_INTERVAL};
use crate::gpu::GpuError;
use crate::render::display::{self, DisplayInputs, DisplayParams, ImageStats};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

/// One dispatch of an engine frame.
enum Dispatch {
    Preview,
    Band { row0: u32, rows: u32, spp: u32 },
}

impl Engine {
    /// Renders one engine frame: a bounded dispatch per active side, the display pass, the readback.
    /// Returns whether anything was rendered.
    pub(super) fn frame(&mut self) -> Result<bool, GpuError> {
        if self.lost.load(Ordering::SeqCst) {
            return Err(GpuError::Poll("the device was lost".into()));
        }
        let n = self.active();
        let budget = FRAME_BUDGET_S / n as f64;
        let mut enc =
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("viewer frame") });
        let mut dispatches: Vec<(usize, Dispatch)> = Vec::new();
        for i in 0..n {
            if !self.choose_pipeline(i) {
                continue;
            }
            let side = &mut self.sides[i];
            let timer = self.timer.as_mut();
            if !side.preview_done {
                side.preview.record(&mut enc, 1, timer);
                dispatches.push((i, Dispatch::Preview));
            } else if side.renderer.samples() < MAX_SPP {
                let (rows, spp) = side.plan(budget);
                let row0 = side.renderer.pass_row();
                let spp = side.renderer.pass_spp().unwrap_or(spp);
                // A guided render learns its environment guide and completes sample 0 before its first band.
                side.renderer.ensure_guide(&self.ctx)?;
                side.renderer.record_band(&mut enc, spp, rows, timer);
                dispatches.push((i, Dispatch::Band { row0, rows, spp }));
            }
        }
        if dispatches.is_empty() && self.frames > 0 && !self.display_dirty() {
            return Ok(false);
        }
        if self.sides.iter().take(n).all(|s| s.pipeline == PipelineState::Compiling) {
            self.publish_stats();
            return Ok(false);
        }
        let (w, h) = (self.settings[0].width, self.settings[0].height);
        let b = if self.compare { 1 } else { 0 };
        let params = DisplayParams {
            width: w,
            height: h,
            view: self.options.view.tag(),
            tonemap: display::tonemap_tag(self.options.tonemap),
            exposure_scale: self.options.exposure.exp2(),
            split_x: if self.compare { (self.options.split.clamp(0.0, 1.0) * w as f32).round() as u32 } else { w },
            compare: self.compare as u32,
            has_reference: self.reference.is_some() as u32,
            preview_scale: PREVIEW_SCALE,
            preview_width: self.sides[0].preview.settings().width,
            preview_height: self.sides[0].preview.settings().height,
            log_min: self.options.log_range[0],
            log_max: self.options.log_range[1],
            row_offset: 0,
            row_count: h,
            ..Default::default()
        };
        // Redraw only the rows rendered this frame, unless everything changed (a restart shows the
        // preview everywhere; display options change every pixel).
        let full =
            self.frames == 0 || self.display_dirty() || dispatches.iter().any(|(_, d)| matches!(d, Dispatch::Preview));
        let params = if full {
            params
        } else {
            let bands = dispatches.iter().filter_map(|(_, d)| match d {
                Dispatch::Band { row0, rows, .. } => Some((*row0, row0 + rows)),
                Dispatch::Preview => None,
            });
            let (lo, hi) = bands.fold((h, 0), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)));
            DisplayParams { row_offset: lo.min(hi), row_count: hi.saturating_sub(lo), ..params }
        };
        // Not in a restart's first frame: its full-resolution accumulators are empty, and the first
        // image should come as fast as possible (the statistics follow in the next frame).
        let preview_frame = dispatches.iter().any(|(_, d)| matches!(d, Dispatch::Preview));
        for (i, d) in &dispatches {
            if matches!(d, Dispatch::Preview) {
                self.image_stats[*i] = ImageStats::default();
                // The panel shows no statistics until the next one; compute them in the first band frame.
                self.stats_pending = true;
            }
        }
        let stats = !preview_frame && (full || self.stats_pending || self.last_stats.elapsed() >= STATS_INTERVAL);
        if stats {
            self.last_stats = Instant::now();
        }
        let ts = self.timer.as_mut().and_then(|t| t.pass());
        let inputs = DisplayInputs {
            accum: [self.sides[0].renderer.accum_buffer(), self.sides[b].renderer.accum_buffer()],
            preview: [self.sides[0].preview.accum_buffer(), self.sides[b].preview.accum_buffer()],
            reference: self.reference.as_ref(),
        };
        self.display.encode(&mut enc, &params, &inputs, stats, ts);
        let t0 = Instant::now();
        self.ctx.queue.submit([enc.finish()]);
        let out = self.display.read(&self.ctx, stats)?;
        let wall = t0.elapsed().as_secs_f64();
        // Seconds of this frame's passes in the order they were recorded: the dispatches, then the display pass.
        let stamps = match self.timer.as_mut() {
            Some(t) => Some(t.read(&self.ctx)?),
            None => None,
        };
        let display_ms = stamps.as_ref().and_then(|s| s.last()).map_or(0.0, |s| s * 1e3);
        // Book-keeping: advance the passes, time the dispatches, update the cost estimates.
        let work: f64 = dispatches.iter().map(|(i, d)| self.dispatch_pixels(*i, d)).sum::<f64>().max(1.0);
        for (k, (i, d)) in dispatches.iter().enumerate() {
            let pixels = self.dispatch_pixels(*i, d);
            let secs = match &stamps {
                Some(s) => s[k],
                None => wall * pixels / work,
            };
            let side = &mut self.sides[*i];
            let kind = (side.pipeline == PipelineState::Specialised) as usize;
            if pixels > 0.0 && secs > 0.0 {
                let measured = secs / pixels;
                side.est[kind] = 0.5 * side.est[kind] + 0.5 * measured;
            }
            side.last_gpu_ms = secs * 1e3;
            match d {
                Dispatch::Preview => {
                    side.preview_done = true;
                    if let Some(t) = side.restarted_at.take() {
                        log::info!(
                            "side {i}: first image {:.0} ms after the restart (preview {:.1} GPU ms, display {:.1} GPU ms, submit to readback {:.1} ms, {:?} pipeline)",
                            t.elapsed().as_secs_f64() * 1e3,
                            secs * 1e3,
                            display_ms,
                            wall * 1e3,
                            side.pipeline
                        );
                    }
                }
                Dispatch::Band { .. } => {
                    side.render_seconds += secs;
                    side.pixel_samples += pixels;
                }
            }
        }
        for i in 0..n {
            if dispatches.iter().any(|(j, d)| *j == i && matches!(d, Dispatch::Band { .. })) {
                self.sides[i].renderer.collect_counters(&self.ctx)?;
            }
        }
        self.frames += 1;
        let frame = Frame {
            width: w,
            height: h,
            rgba: out.rgba,
            serial: self.frames,
            generations: [self.sides[0].generation, self.sides[b].generation],
            shown: [self.sides[0].preview_done, self.sides[b].preview_done],
        };
        {
            let mut s = self.shared();
            s.frame = Some(Arc::new(frame));
            s.frames = self.frames;
            s.display_ms = display_ms;
        }
        self.last_options = Some((self.options, self.reference.is_some(), self.compare));
        if let Some(s) = out.stats {
            self.image_stats = s;
            self.stats_pending = false;
        }
        self.publish_stats();
        Ok(true)
    }

    fn display_dirty(&self) -> bool {
        self.last_options != Some((self.options, self.reference.is_some(), self.compare))
    }

    fn dispatch_pixels(&self, i: usize, d: &Dispatch) -> f64 {
        let s = &self.sides[i];
        match d {
            Dispatch::Preview => (s.preview.settings().width * s.preview.settings().height) as f64,
            Dispatch::Band { rows, spp, .. } => (s.renderer.settings().width * rows * spp) as f64,
        }
    }

    fn publish_stats(&mut self) {
        let n = self.active();
        let mut stats: [SideStats; 2] = Default::default();
        for i in 0..2 {
            let side = &self.sides[i];
            let r = &side.renderer;
            stats[i] = SideStats {
                settings: self.settings[i].clone(),
                env_sampling: r.settings().env_sampling,
                generation: side.generation,
                spp: r.samples(),
                pass_rows: r.pass_row(),
                samples_per_s: if side.render_seconds > 0.0 { side.pixel_samples / side.render_seconds } else { 0.0 },
                mrays_per_s: if side.render_seconds > 0.0 {
                    r.rays_total() as f64 / side.render_seconds / 1e6
                } else {
                    0.0
                },
                gpu_ms: side.last_gpu_ms,
                image: self.image_stats[i],
                nonfinite_samples: r.nonfinite_total(),
                pipeline: if i < n { side.pipeline } else { PipelineState::Compiling },
                shown: side.preview_done,
            };
        }
        {
            let mut s = self.shared();
            s.stats = stats;
        }
        (self.repaint)();
    }
}
