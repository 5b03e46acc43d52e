//! One side's render state (the full-resolution and the preview renderer, cost estimates, restarts) and
//! the band planner that sizes each dispatch to the frame budget.

use super::{PipelineState, PREVIEW_SCALE};
use crate::gpu::GpuContext;
use crate::render::gpu_scene::GpuScene;
use crate::render::settings::Settings;
use crate::render::Renderer;
use crate::scene::Camera;
use crate::viewer::ViewerError;
use std::time::Instant;

/// Per-side render state.
pub(super) struct SideState {
    pub(super) renderer: Renderer,
    pub(super) preview: Renderer,
    pub(super) preview_done: bool,
    /// Seconds per pixel sample, per pipeline kind (0 generic, 1 specialised).
    pub(super) est: [f64; 2],
    /// GPU seconds of full-resolution dispatches since the restart.
    pub(super) render_seconds: f64,
    /// Pixel samples since the restart.
    pub(super) pixel_samples: f64,
    pub(super) generation: u64,
    pub(super) pipeline: PipelineState,
    pub(super) last_gpu_ms: f64,
    /// When the accumulation last restarted (logged with the time to its first image).
    pub(super) restarted_at: Option<Instant>,
}

impl SideState {
    pub(super) fn new(
        ctx: &GpuContext,
        gs: &GpuScene,
        camera: Camera,
        settings: Settings,
    ) -> Result<SideState, ViewerError> {
        let renderer = Renderer::new_unprepared(ctx, gs, camera.clone(), settings.clone())?;
        let preview_settings = Settings {
            width: settings.width.div_ceil(PREVIEW_SCALE),
            height: settings.height.div_ceil(PREVIEW_SCALE),
            ..settings
        };
        let preview = Renderer::new_unprepared(ctx, gs, camera, preview_settings)?;
        Ok(SideState {
            renderer,
            preview,
            preview_done: false,
            // Conservative guesses (lavapipe, 2 cores) until the first dispatch is timed.
            est: [1.0 / 0.1e6, 1.0 / 0.2e6],
            render_seconds: 0.0,
            pixel_samples: 0.0,
            generation: 0,
            pipeline: PipelineState::Compiling,
            last_gpu_ms: 0.0,
            restarted_at: None,
        })
    }

    /// Forgets all samples (the next frame shows a fresh preview).
    pub(super) fn restart(&mut self) {
        self.renderer.reset();
        self.preview.reset();
        self.preview_done = false;
        self.render_seconds = 0.0;
        self.pixel_samples = 0.0;
        self.generation += 1;
        self.restarted_at = Some(Instant::now());
    }

    pub(super) fn set_settings(&mut self, s: Settings) -> Result<(), ViewerError> {
        let (w, h) = (self.renderer.settings().width, self.renderer.settings().height);
        let (pw, ph) = (self.preview.settings().width, self.preview.settings().height);
        self.renderer.configure(Settings { width: w, height: h, ..s.clone() })?;
        self.preview.configure(Settings { width: pw, height: ph, ..s })?;
        self.restart();
        Ok(())
    }

    pub(super) fn set_camera(&mut self, c: Camera) {
        self.renderer.set_camera(c.clone());
        self.preview.set_camera(c);
        self.restart();
    }

    /// Rows and samples per pixel of the next full-resolution dispatch for a budget of `budget` seconds.
    pub(super) fn plan(&self, budget: f64) -> (u32, u32) {
        let (w, h) = (self.renderer.settings().width, self.renderer.settings().height);
        let est = self.est[(self.pipeline == PipelineState::Specialised) as usize];
        let pass_row = self.renderer.pass_row();
        if pass_row == 0 {
            let full = est * (w as f64) * (h as f64);
            if full <= budget {
                let spp = ((budget / full).floor() as u32).clamp(1, 64);
                return (h, spp);
            }
        }
        let rows = (budget / (est * w as f64)).floor() as u32;
        let rows = (rows / 8 * 8).max(8).min(h - pass_row);
        (rows, 1)
    }
}
