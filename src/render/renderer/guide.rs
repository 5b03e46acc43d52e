//! The `Renderer`'s side of the environment guide (`render::env_guide`): whether the settings want one, learning
//! it from sample 0, and how much of it is used.

use super::Renderer;
use crate::gpu::timer::GpuTimer;
use crate::gpu::{GpuContext, GpuError};
use crate::render::env_guide;
use crate::render::scene_data::SceneData;
use crate::render::settings::{EnvSampling, Strategy};
use crate::render::sky_probe::{self, SkyProbe};

impl Renderer {
    /// Whether the settings sample the scene's environment by a guide (`--env-sampling guided`, a constant
    /// environment, a strategy that takes light samples).
    pub fn wants_guide(&self) -> bool {
        let s = &self.settings;
        self.env_is_constant
            && s.env_sampling == EnvSampling::Guided
            && matches!(s.strategy, Strategy::Light | Strategy::Mis)
    }

    /// `--env-sampling auto` made concrete for this renderer's view: guided where the sky probe finds that the
    /// guide would draw enough of the first vertices' light samples (or where it cannot probe a constant sky),
    /// importance elsewhere. Other choices stand.
    pub(super) fn resolved_env_sampling(&self, requested: EnvSampling) -> EnvSampling {
        match (requested, self.sky_probe) {
            (EnvSampling::Auto, Some(p)) if !p.wants_guide() => EnvSampling::Importance,
            (EnvSampling::Auto, _) if self.env_is_constant => EnvSampling::Guided,
            (EnvSampling::Auto, _) => EnvSampling::Importance,
            (s, _) => s,
        }
    }

    /// Traces the sky probe from this renderer's camera over `d`, the scene it renders.
    pub(super) fn probe_sky(&self, d: &SceneData) -> Option<SkyProbe> {
        sky_probe::probe_view(d, &self.camera, self.settings.width, self.settings.height)
    }

    /// What the sky probe saw (`--env-sampling auto`), where it ran.
    pub fn sky_probe(&self) -> Option<SkyProbe> {
        self.sky_probe
    }

    /// Once the environment guide is learned: how many of its slots (region × normal class) draw sky samples from
    /// it, and how many there are.
    pub fn guide_coverage(&self) -> Option<(usize, usize)> {
        self.guide_on.then_some((self.guided_slots, self.guide_grid.slots()))
    }

    /// One 8×8 tile in this many learns the guide (`env_guide::learner_period` of the film unless set).
    pub fn guide_learner_period(&self) -> u32 {
        self.guide_learner_period
            .unwrap_or_else(|| env_guide::learner_period(self.settings.width as u64 * self.settings.height as u64))
    }

    /// Sets how many 8×8 tiles share one learner (1, 2 or 4; None: the film size decides), so that a test can
    /// exercise learner tiles on a small film; resets.
    pub fn set_guide_learner_period(&mut self, period: Option<u32>) {
        assert!(period.is_none_or(|p| matches!(p, 1 | 2 | 4)), "learner period {period:?}: 1, 2 or 4");
        self.guide_learner_period = period;
        self.reset();
    }

    /// Learns the environment guide for the current camera and settings if they want one and it is not learned
    /// yet (`env_guide`): sample 0 of the learner tiles' pixels, rendered with the cosine alone, counts where the
    /// sky was seen; the counts are read back and the CDFs uploaded. At sample 0 that pass is the learner pixels'
    /// first sample, and the other pixels' sample 0 follows at once, guided (`env_guide::COMPLETE`): sample 0 is
    /// then complete. A render resumed (or a part started) past it renders the learners' sample 0 again, counting
    /// only, and so learns the same guide: the image does not depend on where a render was stopped or split. The
    /// pipeline must be built (`prepare`); a band pass in flight waits for its end.
    pub fn ensure_guide(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        self.ensure_guide_timed(ctx, None)
    }

    /// `ensure_guide`, its passes timed by `timer` (benchmarks: `render_timed`).
    pub fn ensure_guide_timed(&mut self, ctx: &GpuContext, mut timer: Option<&mut GpuTimer>) -> Result<(), GpuError> {
        if self.guide_on || self.pass.is_some() || !self.wants_guide() {
            return Ok(());
        }
        let first = self.samples == 0;
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.guide_counts, 0, None);
        self.guide_train = if first { env_guide::LEARN } else { env_guide::LEARN_ONLY };
        let writes = timer.as_deref_mut().and_then(|t| t.pass());
        self.dispatch(&mut enc, 1, self.window.start, self.window.len() as u32, writes);
        self.guide_train = 0;
        self.queue.submit([enc.finish()]);
        ctx.wait()?;
        self.collect_counters(ctx)?;
        let words = env_guide::counts_words(self.guide_grid.slots());
        let counts: Vec<u32> = ctx.read_pod(&self.guide_counts, words)?;
        let cdfs = env_guide::cdfs(&counts, &self.guide_grid, env_guide::POOL_RADIUS);
        self.guided_slots = cdfs.chunks_exact(env_guide::BINS).filter(|c| c[env_guide::BINS - 1] > 0.0).count();
        self.queue.write_buffer(&self.guide_cdf, 0, bytemuck::cast_slice(&cdfs));
        self.guide_on = true;
        if first {
            // The rest of sample 0, with the guide (the write above reaches the queue before this submission).
            let mut enc = self.device.create_command_encoder(&Default::default());
            self.guide_train = env_guide::COMPLETE;
            self.record(&mut enc, 1, timer);
            self.guide_train = 0;
            self.queue.submit([enc.finish()]);
            ctx.wait()?;
            self.collect_counters(ctx)?;
        }
        Ok(())
    }
}
