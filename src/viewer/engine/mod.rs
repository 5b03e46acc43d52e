//! The viewer's render engine: a thread with its own device that renders one or two configurations
//! (A | B) progressively in bands of rows sized to a time budget, builds render pipelines on a worker
//! thread (the generic pipeline serves until the specialised one is ready), runs the display pass and
//! hands finished frames and statistics to the UI.
//!
//! Why a device of its own: on lavapipe a pipeline's first dispatch can compile for seconds (the generic
//! one for tens of seconds on a cold shader cache) and that stalls the queue it runs on. On its own
//! device that stall never blocks the window's drawing; the UI only copies finished RGBA frames.
//!
//! Where things are: `protocol` (commands, shared state, the handle), `compile_worker` (pipeline jobs and
//! the warm-up device), `side` (per-side state and the band planner), `frame` (one engine frame), `recovery`
//! (device loss and recreation), `commands` (how each command changes the engine); this file holds the
//! tuning constants, the engine's state and its loop.

use crate::gpu::timer::GpuTimer;
use crate::gpu::GpuContext;
use crate::render::display::{DisplayPass, ImageStats};
use crate::render::features::PipelineKey;
use crate::render::pipeline_cache::PipelineCache;
use crate::render::settings::Settings;
use crate::render::Renderer;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::{Camera, Scene};
use crate::viewer::ViewerError;
use compile_worker::{CompileJob, Wanted};
use side::SideState;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

mod commands;
mod compile_worker;
mod frame;
mod protocol;
mod recovery;
mod side;

pub use protocol::{
    spawn, Command, DisplayOptions, EngineConfig, EngineHandle, Frame, PipelineState, Shared, Side, SideStats,
};

/// The preview film is the film divided by this in each direction: the first image after a reset is
/// one sample of each preview pixel, shown enlarged until the full-resolution rows replace it.
pub const PREVIEW_SCALE: u32 = 8;
/// GPU time one engine frame aims at, all sides together. It bounds how long a new command waits for
/// the dispatch in flight, and leaves the CPU (lavapipe = the CPU) to the window between frames.
pub const FRAME_BUDGET_S: f64 = 0.020;
/// Sample counts stop growing here (the image has long converged; the CPU goes back to idle).
pub const MAX_SPP: u32 = 1 << 16;
/// How often the statistics are summed over the whole film (they cost a pass over every pixel).
pub const STATS_INTERVAL: Duration = Duration::from_millis(250);
/// Extra pause after the UI has painted a frame, seconds (see `yield_to_ui`).
pub const UI_GAP_S: f64 = 0.008;
/// Longest the engine waits for the UI to take a frame (a hidden window takes none).
pub const UI_WAIT: Duration = Duration::from_millis(150);

struct Engine {
    ctx: GpuContext,
    scene: Scene,
    scene_name: String,
    gs: GpuScene,
    sides: Vec<SideState>,
    compare: bool,
    display: DisplayPass,
    options: DisplayOptions,
    reference: Option<wgpu::Buffer>,
    pipelines: PipelineCache,
    requested: HashSet<PipelineKey>,
    jobs: Sender<CompileJob>,
    compiled: Receiver<(PipelineKey, Result<wgpu::ComputePipeline, String>, f64)>,
    worker_stop: Arc<AtomicBool>,
    timer: Option<GpuTimer>,
    shared: Arc<Mutex<Shared>>,
    repaint: Arc<dyn Fn() + Send + Sync>,
    lost: Arc<AtomicBool>,
    gpu_error: Arc<Mutex<Option<String>>>,
    warm_device: bool,
    generic: bool,
    wanted: Wanted,
    seq: u64,
    /// The settings each requested pipeline was asked for (its warm-up dispatch needs them).
    job_settings: HashMap<PipelineKey, Settings>,
    /// An 8×8 renderer of an empty scene that runs each new pipeline's first (0-sample) dispatch.
    warm: Renderer,
    warm_scene: GpuScene,
    frames: u64,
    settings: [Settings; 2],
    camera: Camera,
    recoveries: u32,
    /// Display inputs of the last frame (a change redraws even when nothing renders).
    last_options: Option<(DisplayOptions, bool, bool)>,
    /// When the statistics were last summed, and their values.
    last_stats: Instant,
    /// A restart cleared the image statistics; the next frame that renders samples computes them.
    stats_pending: bool,
    image_stats: [ImageStats; 2],
}

fn scene_centre(scene: &Scene) -> glam::Vec3 {
    let mut lo = glam::Vec3::splat(f32::INFINITY);
    let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
    let mut add = |p: glam::Vec3| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    for m in &scene.meshes {
        for &p in &m.positions {
            add(p);
        }
    }
    for s in &scene.spheres {
        add(s.center - s.radius);
        add(s.center + s.radius);
    }
    for q in &scene.quads {
        add(q.corner);
        add(q.corner + q.edge_u + q.edge_v);
    }
    if lo.x > hi.x {
        scene.camera.position + scene.camera.forward.normalize_or(glam::Vec3::NEG_Z) * 5.0
    } else {
        0.5 * (lo + hi)
    }
}

impl Engine {
    fn new(
        ctx: GpuContext,
        config: EngineConfig,
        shared: Arc<Mutex<Shared>>,
        repaint: Arc<dyn Fn() + Send + Sync>,
    ) -> Result<Engine, ViewerError> {
        let (w, h) = (config.settings[0].width, config.settings[0].height);
        let gs = GpuScene::upload(&ctx, SceneData::build(&config.scene))
            .map_err(|e| ViewerError::Input(format!("{}: {e}", config.scene_name)))?;
        let camera = config.scene.camera.clone();
        let mut sides = Vec::new();
        for s in &config.settings {
            sides.push(SideState::new(&ctx, &gs, camera.clone(), Settings { width: w, height: h, ..s.clone() })?);
        }
        let display = DisplayPass::new(&ctx, w, h)?;
        let wanted: Wanted = Arc::new(Mutex::new(HashSet::new()));
        let (jobs, compiled, worker_stop) =
            Self::start_worker(&ctx, &sides[0].renderer, config.warm_device, wanted.clone());
        let lost = Arc::new(AtomicBool::new(false));
        let gpu_error = Arc::new(Mutex::new(None));
        Self::watch_device(&ctx, &lost, &gpu_error);
        // A pass per side and the display pass per frame.
        let timer = GpuTimer::new(&ctx, 3);
        let (warm_scene, warm) = Self::warm_renderer(&ctx)?;
        {
            let mut s = shared.lock().unwrap_or_else(|p| p.into_inner());
            s.scene = config.scene_name.clone();
            s.home_camera = camera.clone();
            s.camera = camera.clone();
            s.pivot = scene_centre(&config.scene);
            s.compare = config.compare;
        }
        let mut e = Engine {
            ctx,
            scene: config.scene,
            scene_name: config.scene_name,
            gs,
            sides,
            compare: config.compare,
            display,
            options: config.display,
            reference: None,
            pipelines: PipelineCache::default(),
            requested: HashSet::new(),
            jobs,
            compiled,
            worker_stop,
            timer,
            shared,
            repaint,
            lost,
            gpu_error,
            warm_device: config.warm_device,
            generic: config.generic,
            wanted,
            seq: 0,
            job_settings: HashMap::new(),
            warm,
            warm_scene,
            frames: 0,
            settings: config.settings,
            camera,
            recoveries: 0,
            last_options: None,
            last_stats: Instant::now(),
            stats_pending: false,
            image_stats: Default::default(),
        };
        e.request_pipelines();
        Ok(e)
    }

    fn active(&self) -> usize {
        if self.compare {
            2
        } else {
            1
        }
    }

    fn shared(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn message(&self, m: String) {
        log::info!("{m}");
        self.shared().message = Some(m);
        (self.repaint)();
    }

    fn run(&mut self, rx: Receiver<Command>) {
        let mut idle = false;
        loop {
            // Commands: wait for one while there is nothing to render, else take what is queued.
            let first = if idle {
                match rx.recv_timeout(Duration::from_millis(50)) {
                    Ok(c) => Some(c),
                    Err(RecvTimeoutError::Timeout) => None,
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            } else {
                match rx.try_recv() {
                    Ok(c) => Some(c),
                    Err(TryRecvError::Empty) => None,
                    Err(TryRecvError::Disconnected) => return,
                }
            };
            let mut next = first;
            while let Some(c) = next {
                match self.handle(c) {
                    Ok(true) => {}
                    Ok(false) => {
                        self.worker_stop.store(true, Ordering::SeqCst);
                        return;
                    }
                    Err(e) => self.message(e.to_string()),
                }
                next = rx.try_recv().ok();
            }
            self.collect_compiled();
            if self.shared().fatal.is_some() {
                idle = true;
                continue;
            }
            let result = self.frame();
            let error = self.gpu_error.lock().unwrap_or_else(|p| p.into_inner()).take();
            match (result, error) {
                (Ok(did), None) => {
                    idle = !did;
                    if did {
                        if let Some(c) = self.yield_to_ui(&rx) {
                            match self.handle(c) {
                                Ok(true) => {}
                                Ok(false) => {
                                    self.worker_stop.store(true, Ordering::SeqCst);
                                    return;
                                }
                                Err(e) => self.message(e.to_string()),
                            }
                        }
                    }
                }
                (Err(e), _) => self.recover(e.to_string()),
                (Ok(_), Some(e)) => self.recover(e),
            }
        }
    }

    /// Lavapipe renders the window on the same two cores: after posting a frame, wait until the UI has
    /// taken it and had time to paint (at most `UI_WAIT`), so the window keeps its frame rate. A command
    /// ends the wait at once (it is returned, to be handled before the next dispatch).
    fn yield_to_ui(&self, rx: &Receiver<Command>) -> Option<Command> {
        let start = Instant::now();
        let mut taken_at: Option<Instant> = None;
        loop {
            let (taken, cost) = {
                let s = self.shared();
                (s.ui_painted >= self.frames, s.ui_cost_s)
            };
            if taken && taken_at.is_none() {
                taken_at = Some(Instant::now());
            }
            if let Some(t) = taken_at {
                // The UI's GPU work (rasterising the window on the same CPU) may still run after it
                // began its next frame: leave it a few milliseconds more.
                if t.elapsed().as_secs_f64() >= UI_GAP_S + cost.clamp(0.0, 0.02) {
                    return None;
                }
            }
            if start.elapsed() > UI_WAIT {
                return None;
            }
            match rx.recv_timeout(Duration::from_millis(2)) {
                Ok(c) => return Some(c),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Some(Command::Quit),
            }
        }
    }
}
