//! `render(lab, scene, job, observer) -> Image`, and the render in progress it is made of (`Render`), which a
//! live display advances step by step.

use super::budget::{Budget, RenderStats};
use super::drive::{drive, Plan, SaveCheckpoint};
use super::error::ApiError;
use super::image::Image;
use super::job::Job;
use super::lab::Lab;
use super::observer::{Observer, Startup};
use super::scene::SceneHandle;
use crate::render::settings::Settings;
use crate::render::{reachability, Renderer};
use crate::scene::SceneSpec;
use web_time::Instant;

/// Renders `scene` as `job` says: start-up (upload, pipeline, a resumed state), the one loop to the budget with
/// checkpoints, the state file written at the end, and the image read back. An observer's stop returns what has
/// accumulated, with `interrupted` set (and the state saved, when a sample was rendered).
pub fn render(lab: &Lab, scene: &SceneHandle, job: &mut Job, observer: &mut dyn Observer) -> Result<Image, ApiError> {
    let mut r = Render::begin(lab, scene, job, observer)?;
    let budget = match &job.session {
        Some(s) => Budget::Samples(s.range().1.saturating_sub(r.renderer.samples())),
        None => job.budget,
    };
    let mut dispatch = job.dispatch_spp.unwrap_or_else(|| r.renderer.max_dispatch_spp());
    loop {
        let mut save = |renderer: &Renderer, seconds: f64| match &job.session {
            Some(s) => s.save(lab.gpu(), renderer, seconds).map_err(ApiError::from),
            None => Ok(()),
        };
        let checkpoint = job.session.as_ref().and_then(|s| s.every()).map(|every| (every, &mut save as SaveCheckpoint));
        let stats = r.advance(lab, Plan { budget, submit_seconds: job.submit_seconds, checkpoint }, observer)?;
        // A driver that silently cuts long dispatches short (lavapipe 22.3's loop budget) leaves pixels with
        // fewer samples than rendered: redo with half as many samples per dispatch.
        let check = job.verify_complete && job.session.is_none() && !stats.interrupted;
        if !check || matches!(budget, Budget::Time(_)) || r.renderer.film(lab.gpu())?.is_complete(stats.spp) {
            break;
        }
        if dispatch == 1 {
            return Err(ApiError::Device("pixels miss samples even with 1 spp per dispatch".into()));
        }
        dispatch /= 2;
        observer.note(&format!(
            "note: the driver dropped samples (a per-invocation loop budget); rendering again with {dispatch} spp per dispatch"
        ));
        r.renderer.reset();
        r.renderer.set_dispatch_spp(Some(dispatch));
        r.stats = RenderStats::default();
    }
    if let Some(s) = &job.session {
        // Nothing to save when a stop came before the first sample: the state on disk is still right.
        if !(r.stats.interrupted && r.stats.spp == 0) {
            s.save(lab.gpu(), &r.renderer, r.stats.seconds).map_err(ApiError::from)?;
        }
    }
    r.image(lab)
}

/// A render in progress: the renderer set up for one scene and settings, and what it has done so far.
pub struct Render {
    renderer: Renderer,
    scene: SceneSpec,
    settings: Settings,
    first_sample: u32,
    stats: RenderStats,
}

impl Render {
    /// Start-up: the scene on the device, the pipeline compiled (or found in the lab), the fixed-count samplers
    /// set to the budget, a resumed state restored or a part's first sample index set. Notes and warnings go to
    /// the observer; a stop requested during start-up is seen by the first `advance`.
    pub fn begin(
        lab: &Lab,
        scene: &SceneHandle,
        job: &mut Job,
        observer: &mut dyn Observer,
    ) -> Result<Render, ApiError> {
        let t0 = Instant::now();
        for note in job.resolve(scene) {
            observer.note(&format!("note: {note}"));
        }
        let settings = job.settings.clone();
        if let Some(w) = reachability::unreachable_light_warning(scene.data(), &settings) {
            observer.note(&format!("warning: {w}"));
        }
        let ctx = lab.gpu();
        let t_upload = Instant::now();
        let gpu_scene = scene.upload(lab)?;
        let scene_upload = t_upload.elapsed().as_secs_f64();
        let (mut renderer, [buffers, pipeline, first_dispatch]) =
            Renderer::new_timed(ctx, &gpu_scene, scene.camera().clone(), settings.clone())?;
        let mut startup = Startup { upload: scene_upload + buffers, pipeline, first_dispatch, ..Startup::default() };
        if let Budget::Samples(n) = job.budget {
            renderer.set_sampler_spp(n);
        }
        renderer.set_dispatch_spp(job.dispatch_spp);
        if let (Some(s), Budget::Samples(n)) = (job.session.as_mut(), job.budget) {
            s.start(&mut renderer, &scene.spec().scene, scene.hash().to_string(), &settings, n, n)
                .map_err(ApiError::from)?;
        }
        ctx.wait()?;
        startup.seconds = t0.elapsed().as_secs_f64();
        observer.started(&startup);
        let first_sample = renderer.samples();
        Ok(Render { renderer, scene: scene.spec().clone(), settings, first_sample, stats: RenderStats::default() })
    }

    /// Renders on to `plan`'s budget (counted from here); returns the totals since `begin`.
    pub fn advance(&mut self, lab: &Lab, plan: Plan<'_>, observer: &mut dyn Observer) -> Result<RenderStats, ApiError> {
        let step = drive(lab.gpu(), &mut self.renderer, plan, observer)?;
        let s = &mut self.stats;
        s.spp += step.spp;
        s.extra_rows = step.extra_rows;
        s.seconds += step.seconds;
        s.rays += step.rays;
        s.nonfinite = step.nonfinite;
        s.interrupted = step.interrupted;
        Ok(s.clone())
    }

    /// The image so far (read back from the device).
    pub fn image(&self, lab: &Lab) -> Result<Image, ApiError> {
        Ok(Image {
            film: self.renderer.film(lab.gpu())?,
            stats: self.stats.clone(),
            settings: self.settings.clone(),
            scene: self.scene.clone(),
            sample_range: (self.first_sample, self.renderer.samples()),
            guide_coverage: self.renderer.guide_coverage(),
            sky_probe: self.renderer.sky_probe(),
        })
    }
}
