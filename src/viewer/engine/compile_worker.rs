//! Pipeline jobs: the worker thread that builds render pipelines off the render thread (warming each on a
//! second device first, see [`compile_worker`]), and the engine's side of it: which pipelines to ask for,
//! in what order, taking the built ones in, and choosing the one a side renders with.

use super::side::SideState;
use super::{Engine, PipelineState};
use crate::gpu::{GpuContext, PipelineMemo};
use crate::render::features::PipelineKey;
use crate::render::settings::{Settings, Strategy};
use crate::render::Renderer;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::{Camera, Scene};
use crate::viewer::ViewerError;
use std::collections::HashSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A pipeline the worker should build.
pub(super) struct CompileJob {
    key: PipelineKey,
    /// The module to build it from (`Renderer::source_for`: baked pipelines belong to one scene).
    source: Arc<String>,
    settings: Settings,
    /// Lower first.
    priority: u32,
    /// Request order.
    seq: u64,
}

/// The pipelines the engine still needs (the worker skips jobs that are no longer in it).
pub(super) type Wanted = Arc<Mutex<HashSet<PipelineKey>>>;

/// The worker's answer for a job it skipped.
const SKIPPED: &str = "skipped";

const PRIORITY_NOW: u32 = 0;
const PRIORITY_SPECULATIVE: u32 = 1;
const PRIORITY_GENERIC: u32 = 2;

/// How long the first dispatch of a new pipeline may take: lavapipe compiles it then, which took up
/// to ~40 s for the generic pipeline on an idle 2-core machine with a cold shader cache, minutes under load.
const WARM_UP_TIMEOUT: Duration = Duration::from_secs(900);

/// Builds pipelines for the render device. With `warm`, each pipeline is first built and dispatched
/// (0 samples) on that second device: lavapipe compiles at the first dispatch and keeps the machine
/// code in Mesa's shader cache, so the render device's own first dispatch finds it there instead of
/// stalling its queue for the whole compile.
fn compile_worker(
    device: wgpu::Device,
    memo: PipelineMemo,
    layout: wgpu::PipelineLayout,
    warm: Option<GpuContext>,
    jobs: Receiver<CompileJob>,
    done: Sender<(PipelineKey, Result<wgpu::ComputePipeline, String>, f64)>,
    stop: Arc<AtomicBool>,
    wanted: Wanted,
) {
    let warm = warm.and_then(|c| {
        let gs = GpuScene::upload(&c, SceneData::build(&Scene::default())).ok()?;
        let r = Renderer::new_unprepared(
            &c,
            &gs,
            Camera::default(),
            Settings { width: 8, height: 8, ..Settings::default() },
        )
        .ok()?;
        Some((c, gs, r))
    });
    let mut warm = warm;
    let mut queue: Vec<CompileJob> = Vec::new();
    loop {
        if queue.is_empty() {
            match jobs.recv() {
                Ok(j) => queue.push(j),
                Err(_) => return,
            }
        }
        while let Ok(j) = jobs.try_recv() {
            queue.push(j);
        }
        if stop.load(Ordering::SeqCst) {
            return;
        }
        // Most urgent first; among equals the newest (the settings the user has now).
        queue.sort_by_key(|j| (j.priority, std::cmp::Reverse(j.seq)));
        let job = queue.remove(0);
        if !wanted.lock().unwrap_or_else(|p| p.into_inner()).contains(&job.key) {
            // The settings moved on before this pipeline was started: skip it (the engine asks again
            // if it needs it).
            if done.send((job.key, Err(SKIPPED.into()), 0.0)).is_err() {
                return;
            }
            continue;
        }
        let t = Instant::now();
        if let Some((c, _, r)) = warm.as_mut() {
            r.set_baked_source(&job.source);
            if r.aim_at(job.key, job.settings.clone()) {
                let _ = r.prepare().and_then(|_| Ok(r.warm_up(c)?));
            }
        }
        let constants = job.key.constants();
        let result = crate::render::shaders::compute_pipeline(
            &device,
            memo.store(),
            "render",
            &job.source,
            "render_main",
            &constants,
            Some(&layout),
        );
        if done.send((job.key, result, t.elapsed().as_secs_f64())).is_err() {
            return;
        }
    }
}

impl Engine {
    pub(super) fn start_worker(
        ctx: &GpuContext,
        layout_of: &Renderer,
        warm_device: bool,
        wanted: Wanted,
    ) -> (Sender<CompileJob>, Receiver<(PipelineKey, Result<wgpu::ComputePipeline, String>, f64)>, Arc<AtomicBool>)
    {
        let (jobs_tx, jobs_rx) = mpsc::channel();
        let (done_tx, done_rx) = mpsc::channel();
        let stop = Arc::new(AtomicBool::new(false));
        let warm =
            if warm_device { GpuContext::from_adapter(ctx.instance.clone(), ctx.adapter.clone()).ok() } else { None };
        let (device, memo) = (ctx.device.clone(), ctx.pipelines.clone());
        let layout = layout_of.pipeline_layout().clone();
        let stop2 = stop.clone();
        std::thread::Builder::new()
            .name("mislab-compile".into())
            .spawn(move || compile_worker(device, memo, layout, warm, jobs_rx, done_tx, stop2, wanted))
            .expect("spawning the pipeline compiler thread");
        (jobs_tx, done_rx, stop)
    }

    pub(super) fn warm_renderer(ctx: &GpuContext) -> Result<(GpuScene, Renderer), ViewerError> {
        let gs = GpuScene::upload(ctx, SceneData::build(&Scene::default()))?;
        let r = Renderer::new_unprepared(
            ctx,
            &gs,
            Camera::default(),
            Settings { width: 8, height: 8, ..Settings::default() },
        )?;
        Ok((gs, r))
    }

    fn request(&mut self, key: PipelineKey, settings: &Settings, priority: u32) {
        self.update_wanted();
        if self.pipelines.contains(&key) || !self.requested.insert(key) {
            return;
        }
        self.job_settings.insert(key, settings.clone());
        self.seq += 1;
        let source = Arc::new(self.sides[0].renderer.source_for(&key).to_string());
        let _ = self.jobs.send(CompileJob { key, source, settings: settings.clone(), priority, seq: self.seq });
    }

    /// The keys the active sides need now, their every-strategy neighbours, and the generic one.
    fn update_wanted(&self) {
        let mut w = self.wanted.lock().unwrap_or_else(|p| p.into_inner());
        w.clear();
        for side in self.sides.iter().take(self.active()) {
            for (key, _) in Self::neighbours(side) {
                w.insert(key);
            }
        }
        if self.generic {
            w.insert(PipelineKey::generic());
        }
    }

    /// The specialised pipelines a side needs now (first) and after a strategy toggle (the lecture's
    /// main comparison): built ahead so that such a toggle shows its first image at once.
    fn neighbours(side: &SideState) -> Vec<(PipelineKey, Settings)> {
        let s = side.renderer.settings();
        let mut v = vec![(PipelineKey::specialized(side.renderer.features(), s), s.clone())];
        for st in Strategy::ALL {
            let n = Settings { strategy: *st, ..s.clone() };
            let k = PipelineKey::specialized(side.renderer.features(), &n);
            if !v.iter().any(|(x, _)| *x == k) {
                v.push((k, n));
            }
        }
        v
    }

    /// Asks for the specialised pipelines of the active sides first, then the generic one.
    pub(super) fn request_pipelines(&mut self) {
        for i in 0..self.active() {
            for (n, (key, s)) in Self::neighbours(&self.sides[i]).into_iter().enumerate() {
                self.request(key, &s, if n == 0 { PRIORITY_NOW } else { PRIORITY_SPECULATIVE });
            }
        }
        if self.generic {
            let s = self.sides[0].renderer.settings().clone();
            self.request(PipelineKey::generic(), &s, PRIORITY_GENERIC);
        }
    }

    pub(super) fn collect_compiled(&mut self) {
        loop {
            match self.compiled.try_recv() {
                Ok((key, Ok(p), secs)) => {
                    let t = Instant::now();
                    let warmed = self.warm_up(key, &p);
                    log::info!(
                        "pipeline {} built in {secs:.2} s (worker thread), first dispatch {:.2} s (render thread)",
                        if key.fixed.is_some() { "specialised" } else { "generic" },
                        t.elapsed().as_secs_f64()
                    );
                    self.requested.remove(&key);
                    match warmed {
                        Ok(()) => {
                            self.pipelines.insert(key, p);
                        }
                        Err(e) => *self.gpu_error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e),
                    }
                }
                Ok((key, Err(e), _)) => {
                    self.requested.remove(&key);
                    if e != SKIPPED {
                        self.shared().fatal = Some(format!("a render pipeline failed to build: {e}"));
                    }
                }
                Err(_) => break,
            }
        }
        self.shared().compiling = self.requested.len();
    }

    /// Runs a 0-sample dispatch of a new pipeline on the render device: lavapipe compiles the shader
    /// at its first dispatch (seconds; tens of seconds for the generic pipeline on a cold cache), and
    /// that must not count as a frame (nor time out like one).
    fn warm_up(&mut self, key: PipelineKey, p: &wgpu::ComputePipeline) -> Result<(), String> {
        let settings = self.job_settings.get(&key).cloned().unwrap_or_default();
        let w = &mut self.warm;
        if !w.aim_at(key, settings) {
            return Ok(());
        }
        w.insert_pipeline(key, p.clone());
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
        w.record_warm_up(&mut enc);
        self.ctx.queue.submit([enc.finish()]);
        self.ctx
            .device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: Some(WARM_UP_TIMEOUT) })
            .map(|_| ())
            .map_err(|e| format!("compiling a pipeline: {e}"))
    }

    /// Chooses the pipeline of side `i` (specialised if built, else generic if built) and hands it to
    /// its renderers. False when neither is ready.
    pub(super) fn choose_pipeline(&mut self, i: usize) -> bool {
        let spec = PipelineKey::specialized(self.sides[i].renderer.features(), self.sides[i].renderer.settings());
        let generic = PipelineKey::generic();
        let s = self.sides[i].renderer.settings().clone();
        let (key, state) = if self.pipelines.contains(&spec) {
            (spec, PipelineState::Specialised)
        } else {
            self.request(spec, &s, PRIORITY_NOW);
            if self.pipelines.contains(&generic) {
                (generic, PipelineState::Generic)
            } else {
                self.sides[i].pipeline = PipelineState::Compiling;
                return false;
            }
        };
        let p = self.pipelines.get(&key).expect("checked above").clone();
        let side = &mut self.sides[i];
        side.pipeline = state;
        for r in [&mut side.renderer, &mut side.preview] {
            if !r.has_pipeline(&key) {
                r.insert_pipeline(key, p.clone());
            }
            // The pipeline is in the renderer's cache now: this only selects it.
            if let Err(e) = r.set_specialize(state == PipelineState::Specialised) {
                log::error!("selecting a built pipeline: {e}");
                return false;
            }
        }
        true
    }
}
