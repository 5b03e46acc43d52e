//! The viewer's render engine: a thread with its own device that renders one or two configurations
//! (A | B) progressively in bands of rows sized to a time budget, builds render pipelines on a worker
//! thread (the generic pipeline serves until the specialised one is ready), runs the display pass and
//! hands finished frames and statistics to the UI.
//!
//! Why a device of its own: on lavapipe a pipeline's first dispatch can compile for seconds (the generic
//! one for tens of seconds on a cold shader cache) and that stalls the queue it runs on. On its own
//! device that stall never blocks the window's drawing; the UI only copies finished RGBA frames.

use super::display::{self, DisplayInputs, DisplayParams, DisplayPass, ImageStats, View};
use crate::features::PipelineKey;
use crate::film::Tonemap;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{GpuScene, SceneData};
use crate::gpu_timer::GpuTimer;
use crate::pipeline_cache::PipelineCache;
use crate::render::Renderer;
use crate::scene::{self, Camera, Environment, LoadOptions, Scene};
use crate::settings::{Settings, Strategy};
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

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

/// One side of a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// The left side (the only one without a comparison).
    A = 0,
    /// The right side.
    B = 1,
}

/// How the image is shown (nothing here restarts the accumulation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayOptions {
    /// What is shown.
    pub view: View,
    /// Tonemapper.
    pub tonemap: Tonemap,
    /// Exposure in stops.
    pub exposure: f32,
    /// Divider position as a fraction of the width (A left of it, B right).
    pub split: f32,
    /// log10 of the bottom and the top of the false-colour scale.
    pub log_range: [f32; 2],
}

impl Default for DisplayOptions {
    fn default() -> Self {
        DisplayOptions { view: View::Image, tonemap: Tonemap::Clamp, exposure: 0.0, split: 0.5, log_range: [-4.0, 0.0] }
    }
}

/// What the UI asks of the engine.
pub enum Command {
    /// New estimator settings for a side (restarts that side unless only the exposure changed).
    Settings(Side, Settings),
    /// Render side B too.
    Compare(bool),
    /// New camera (restarts both sides).
    Camera(Camera),
    /// Display options.
    Display(DisplayOptions),
    /// Load a scene (file or built-in name).
    OpenScene(String),
    /// Light the scene with an equirectangular map.
    OpenEnv(PathBuf),
    /// Load a reference EXR of the film's size.
    LoadReference(PathBuf),
    /// Forget the reference.
    ClearReference,
    /// Write side A's film (and B's, as `<stem>-b.exr`) as linear EXR.
    SaveExr(PathBuf),
    /// Destroys the render device, as a driver reset would (tests the recovery path).
    LoseDevice,
    /// Stop the thread.
    Quit,
}

/// Which pipeline a side renders with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PipelineState {
    /// Nothing to render with yet (the first pipeline is compiling).
    #[default]
    Compiling,
    /// The generic pipeline (settings read at run time) while the specialised one compiles.
    Generic,
    /// The pipeline specialised to the scene and settings.
    Specialised,
}

impl PipelineState {
    /// For the panel.
    pub fn describe(self) -> &'static str {
        match self {
            PipelineState::Compiling => "compiling the first pipeline…",
            PipelineState::Generic => "generic pipeline (specialised one compiling)",
            PipelineState::Specialised => "specialised pipeline",
        }
    }
}

/// One side's numbers, as the panel shows them.
#[derive(Clone, Debug, Default)]
pub struct SideStats {
    /// Settings in force.
    pub settings: Settings,
    /// Increments at every restart of the accumulation.
    pub generation: u64,
    /// Complete samples per pixel.
    pub spp: u32,
    /// Rows of the pass in progress that are done.
    pub pass_rows: u32,
    /// Pixel samples per second of GPU time since the restart.
    pub samples_per_s: f64,
    /// Million rays per second of GPU time since the restart.
    pub mrays_per_s: f64,
    /// GPU milliseconds of this side's last dispatch (timestamp queries, or wall time without them).
    pub gpu_ms: f64,
    /// Image statistics of the full-resolution accumulation.
    pub image: ImageStats,
    /// NaN/Inf samples counted since the restart.
    pub nonfinite_samples: u64,
    /// Pipeline in use.
    pub pipeline: PipelineState,
    /// Whether the frame shows this generation's samples (preview or better).
    pub shown: bool,
}

/// A finished frame: what the image area shows.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Film width.
    pub width: u32,
    /// Film height.
    pub height: u32,
    /// RGBA8 sRGB pixels.
    pub rgba: Vec<u8>,
    /// Frame counter.
    pub serial: u64,
    /// The generation of each side this frame shows.
    pub generations: [u64; 2],
    /// Whether each side's part shows samples of that generation (its preview or better).
    pub shown: [bool; 2],
}

/// State shared with the UI.
#[derive(Default)]
pub struct Shared {
    /// The latest frame (the UI takes it).
    pub frame: Option<Arc<Frame>>,
    /// Per-side statistics.
    pub stats: [SideStats; 2],
    /// Whether side B is rendered.
    pub compare: bool,
    /// Scene name.
    pub scene: String,
    /// The scene's own camera (what "reset camera" returns to).
    pub home_camera: Camera,
    /// The camera in force.
    pub camera: Camera,
    /// A point the camera orbits about (the scene's centre).
    pub pivot: glam::Vec3,
    /// The last message for the status line (errors, saves, loads).
    pub message: Option<String>,
    /// Set when the engine has stopped for good; the reason.
    pub fatal: Option<String>,
    /// Frames finished.
    pub frames: u64,
    /// Whether a reference is loaded.
    pub has_reference: bool,
    /// Device recoveries so far.
    pub recoveries: u32,
    /// Render device name.
    pub device: String,
    /// Display GPU milliseconds of the last frame.
    pub display_ms: f64,
    /// Pipelines being compiled, for the status line.
    pub compiling: usize,
    /// The serial of the last frame the UI took.
    pub ui_taken: u64,
    /// The serial of the last frame the UI has painted (it started a later UI frame since).
    pub ui_painted: u64,
    /// Seconds the UI's last frame took (building + painting): the engine leaves the CPU to the UI
    /// this long after each frame.
    pub ui_cost_s: f64,
}

/// The UI's handle on the engine thread.
pub struct EngineHandle {
    tx: Sender<Command>,
    shared: Arc<Mutex<Shared>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl EngineHandle {
    /// Sends a command (ignored once the engine has stopped).
    pub fn send(&self, c: Command) {
        let _ = self.tx.send(c);
    }
    /// The shared state.
    pub fn shared(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }
    /// Waits until `cond` holds on the shared state, at most `timeout`. For tests and screenshots.
    pub fn wait_for(&self, timeout: Duration, mut cond: impl FnMut(&Shared) -> bool) -> bool {
        let t = Instant::now();
        loop {
            if cond(&self.shared()) {
                return true;
            }
            if t.elapsed() > timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

impl Drop for EngineHandle {
    fn drop(&mut self) {
        let _ = self.tx.send(Command::Quit);
        if let Some(t) = self.thread.take() {
            // A dispatch that compiles a pipeline can take long on lavapipe: wait a little, then leave
            // the thread to end with the process rather than hang the window's close.
            let start = Instant::now();
            while !t.is_finished() && start.elapsed() < Duration::from_secs(3) {
                std::thread::sleep(Duration::from_millis(10));
            }
            if t.is_finished() {
                let _ = t.join();
            }
        }
    }
}

/// What the engine starts with.
pub struct EngineConfig {
    /// The scene.
    pub scene: Scene,
    /// Scene name (for the panel and for reloading).
    pub scene_name: String,
    /// Settings of side A and B (their film size is the film size).
    pub settings: [Settings; 2],
    /// Render side B.
    pub compare: bool,
    /// Display options.
    pub display: DisplayOptions,
    /// Warm each pipeline on a second device before the render device uses it (see `compile_worker`).
    pub warm_device: bool,
    /// Build the generic pipeline (used after a toggle until the specialised one is built).
    pub generic: bool,
}

/// Starts the engine thread on `ctx` (the render device). `repaint` is called after every frame.
pub fn spawn(ctx: GpuContext, config: EngineConfig, repaint: Arc<dyn Fn() + Send + Sync>) -> EngineHandle {
    let (tx, rx) = mpsc::channel();
    let shared = Arc::new(Mutex::new(Shared { device: ctx.info.name.clone(), ..Default::default() }));
    let shared2 = shared.clone();
    let thread = std::thread::Builder::new()
        .name("mislab-render".into())
        .spawn(move || {
            let shared3 = shared2.clone();
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || {
                engine_main(ctx, config, rx, shared2, repaint)
            }));
            if let Err(p) = result {
                let what = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                let mut s = shared3.lock().unwrap_or_else(|p| p.into_inner());
                s.fatal = Some(format!("the render thread failed: {what}"));
            }
        })
        .expect("spawning the render thread");
    EngineHandle { tx, shared, thread: Some(thread) }
}

fn engine_main(
    ctx: GpuContext,
    config: EngineConfig,
    rx: Receiver<Command>,
    shared: Arc<Mutex<Shared>>,
    repaint: Arc<dyn Fn() + Send + Sync>,
) {
    let mut engine = match Engine::new(ctx, config, shared.clone(), repaint.clone()) {
        Ok(e) => e,
        Err(e) => {
            shared.lock().unwrap_or_else(|p| p.into_inner()).fatal = Some(e);
            repaint();
            return;
        }
    };
    engine.run(rx);
}

/// A pipeline the worker should build.
struct CompileJob {
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
type Wanted = Arc<Mutex<HashSet<PipelineKey>>>;

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
                let _ = r.prepare().and_then(|_| r.warm_up(c).map_err(|e| e.to_string()));
            }
        }
        let constants = job.key.constants();
        let result =
            crate::shaders::compute_pipeline(&device, "render", &job.source, "render_main", &constants, Some(&layout));
        if done.send((job.key, result, t.elapsed().as_secs_f64())).is_err() {
            return;
        }
    }
}

/// Per-side render state.
struct SideState {
    renderer: Renderer,
    preview: Renderer,
    preview_done: bool,
    /// Seconds per pixel sample, per pipeline kind (0 generic, 1 specialised).
    est: [f64; 2],
    /// GPU seconds of full-resolution dispatches since the restart.
    render_seconds: f64,
    /// Pixel samples since the restart.
    pixel_samples: f64,
    generation: u64,
    pipeline: PipelineState,
    last_gpu_ms: f64,
    /// When the accumulation last restarted (logged with the time to its first image).
    restarted_at: Option<Instant>,
}

impl SideState {
    fn new(ctx: &GpuContext, gs: &GpuScene, camera: Camera, settings: Settings) -> Result<SideState, String> {
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
    fn restart(&mut self) {
        self.renderer.reset();
        self.preview.reset();
        self.preview_done = false;
        self.render_seconds = 0.0;
        self.pixel_samples = 0.0;
        self.generation += 1;
        self.restarted_at = Some(Instant::now());
    }

    fn set_settings(&mut self, s: Settings) -> Result<(), String> {
        let (w, h) = (self.renderer.settings().width, self.renderer.settings().height);
        let (pw, ph) = (self.preview.settings().width, self.preview.settings().height);
        self.renderer.configure(Settings { width: w, height: h, ..s.clone() })?;
        self.preview.configure(Settings { width: pw, height: ph, ..s })?;
        self.restart();
        Ok(())
    }

    fn set_camera(&mut self, c: Camera) {
        self.renderer.set_camera(c.clone());
        self.preview.set_camera(c);
        self.restart();
    }

    /// Rows and samples per pixel of the next full-resolution dispatch for a budget of `budget` seconds.
    fn plan(&self, budget: f64) -> (u32, u32) {
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

/// One dispatch of an engine frame.
enum Dispatch {
    Preview,
    Band { row0: u32, rows: u32, spp: u32 },
}

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
    ) -> Result<Engine, String> {
        let (w, h) = (config.settings[0].width, config.settings[0].height);
        let gs = GpuScene::upload(&ctx, SceneData::build(&config.scene))
            .map_err(|e| format!("{}: {e}", config.scene_name))?;
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
            image_stats: Default::default(),
        };
        e.request_pipelines();
        Ok(e)
    }

    fn start_worker(
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
        let device = ctx.device.clone();
        let layout = layout_of.pipeline_layout().clone();
        let stop2 = stop.clone();
        std::thread::Builder::new()
            .name("mislab-compile".into())
            .spawn(move || compile_worker(device, layout, warm, jobs_rx, done_tx, stop2, wanted))
            .expect("spawning the pipeline compiler thread");
        (jobs_tx, done_rx, stop)
    }

    fn warm_renderer(ctx: &GpuContext) -> Result<(GpuScene, Renderer), String> {
        let gs = GpuScene::upload(ctx, SceneData::build(&Scene::default()))?;
        let r = Renderer::new_unprepared(
            ctx,
            &gs,
            Camera::default(),
            Settings { width: 8, height: 8, ..Settings::default() },
        )?;
        Ok((gs, r))
    }

    fn watch_device(ctx: &GpuContext, lost: &Arc<AtomicBool>, gpu_error: &Arc<Mutex<Option<String>>>) {
        let l = lost.clone();
        let err = gpu_error.clone();
        ctx.device.set_device_lost_callback(move |reason, msg| {
            l.store(true, Ordering::SeqCst);
            *err.lock().unwrap_or_else(|p| p.into_inner()) = Some(format!("device lost ({reason:?}): {msg}"));
        });
        // Without a handler wgpu panics on errors; keep the first one and recover from it instead.
        let err = gpu_error.clone();
        ctx.device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = err.lock().unwrap_or_else(|p| p.into_inner());
            if slot.is_none() {
                *slot = Some(e.to_string());
            }
        }));
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
    fn request_pipelines(&mut self) {
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

    fn collect_compiled(&mut self) {
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
    fn choose_pipeline(&mut self, i: usize) -> bool {
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

    fn handle(&mut self, c: Command) -> Result<bool, String> {
        match c {
            Command::Quit => return Ok(false),
            Command::Settings(side, s) => {
                s.validate()?;
                let i = side as usize;
                let old = &self.settings[i];
                let same_estimator = Settings { exposure: 0.0, width: 0, height: 0, ..old.clone() }
                    == Settings { exposure: 0.0, width: 0, height: 0, ..s.clone() };
                self.settings[i] = s.clone();
                if !same_estimator {
                    self.sides[i].set_settings(s)?;
                    if i < self.active() {
                        self.request_pipelines();
                    }
                }
            }
            Command::Compare(on) => {
                if on != self.compare {
                    self.compare = on;
                    self.shared().compare = on;
                    if on {
                        self.sides[1].restart();
                        self.request_pipelines();
                    }
                }
            }
            Command::Camera(c) => {
                self.camera = c.clone();
                for s in &mut self.sides {
                    s.set_camera(c.clone());
                }
                self.shared().camera = c;
            }
            Command::Display(d) => self.options = d,
            Command::OpenScene(name) => {
                let hook = std::panic::take_hook();
                std::panic::set_hook(Box::new(|_| {}));
                let loaded = scene::load(&name, &LoadOptions::default());
                std::panic::set_hook(hook);
                match loaded {
                    Ok(sc) => {
                        let warnings = sc.warnings.len();
                        self.set_scene(sc, name.clone())?;
                        self.message(format!(
                            "opened {name}{}",
                            if warnings > 0 { format!(" ({warnings} warnings)") } else { String::new() }
                        ));
                    }
                    Err(e) => self.message(format!("could not open the scene: {e}")),
                }
            }
            Command::OpenEnv(path) => match scene::envmap::load_envmap(&path) {
                Ok((map, _)) => {
                    let mut sc = self.scene.clone();
                    sc.environment = Environment::Map { map: Arc::new(map), scale: 1.0, rotation: 0.0 };
                    let name = self.scene_name.clone();
                    let camera = self.camera.clone();
                    self.set_scene(sc, name)?;
                    // Lighting changed, the view did not: keep the user's camera.
                    for s in &mut self.sides {
                        s.set_camera(camera.clone());
                    }
                    self.camera = camera.clone();
                    self.shared().camera = camera;
                    self.message(format!("environment {}", path.display()));
                }
                Err(e) => self.message(format!("could not load the environment: {e}")),
            },
            Command::LoadReference(path) => {
                let (w, h) = (self.settings[0].width, self.settings[0].height);
                match display::load_reference(&path, w, h) {
                    Ok(rgb) => {
                        self.reference = Some(display::upload_reference(&self.ctx, &rgb));
                        self.shared().has_reference = true;
                        self.message(format!("reference {}", path.display()));
                    }
                    Err(e) => self.message(format!("could not load the reference: {e}")),
                }
            }
            Command::ClearReference => {
                self.reference = None;
                self.shared().has_reference = false;
            }
            Command::SaveExr(path) => {
                let mut written = vec![];
                for i in 0..self.active() {
                    let p = if i == 0 {
                        path.clone()
                    } else {
                        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
                        path.with_file_name(format!("{stem}-b.exr"))
                    };
                    let film = self.sides[i].renderer.film(&self.ctx).map_err(|e| e.to_string())?;
                    match film.save(&p, self.options.exposure, self.options.tonemap) {
                        Ok(()) => written.push(p.display().to_string()),
                        Err(e) => {
                            self.message(e);
                            return Ok(true);
                        }
                    }
                }
                self.message(format!("wrote {}", written.join(", ")));
            }
            Command::LoseDevice => self.ctx.device.destroy(),
        }
        Ok(true)
    }

    fn set_scene(&mut self, sc: Scene, name: String) -> Result<(), String> {
        let gs = match GpuScene::upload(&self.ctx, SceneData::build(&sc)) {
            Ok(g) => g,
            Err(e) => {
                self.message(format!("{name}: {e}"));
                return Ok(());
            }
        };
        let camera = sc.camera.clone();
        let mut sides = Vec::new();
        for s in &self.settings {
            sides.push(SideState::new(&self.ctx, &gs, camera.clone(), s.clone())?);
        }
        self.gs = gs;
        self.sides = sides;
        self.camera = camera.clone();
        {
            let mut s = self.shared.lock().unwrap_or_else(|p| p.into_inner());
            s.scene = name.clone();
            s.home_camera = camera.clone();
            s.camera = camera;
            s.pivot = scene_centre(&sc);
        }
        self.scene = sc;
        self.scene_name = name;
        self.request_pipelines();
        Ok(())
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
                    Err(e) => self.message(e),
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
                                Err(e) => self.message(e),
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

    /// Recreates the device and everything on it after a device loss or a GPU error; gives up (with
    /// a message, never a hang) after three failures.
    fn recover(&mut self, why: String) {
        self.recoveries += 1;
        log::warn!("render device error: {why}");
        if self.recoveries > 3 {
            self.shared().fatal =
                Some(format!("the GPU device failed repeatedly ({why}); close the window and restart mislab"));
            (self.repaint)();
            return;
        }
        self.message(format!("GPU error ({why}): recreating the device…"));
        let attempt = (|| -> Result<(), String> {
            let ctx = GpuContext::new().map_err(|e| e.to_string())?;
            let gs = GpuScene::upload(&ctx, SceneData::build(&self.scene))?;
            let mut sides = Vec::new();
            for s in &self.settings {
                sides.push(SideState::new(&ctx, &gs, self.camera.clone(), s.clone())?);
            }
            let (w, h) = (self.settings[0].width, self.settings[0].height);
            let display = DisplayPass::new(&ctx, w, h)?;
            self.worker_stop.store(true, Ordering::SeqCst);
            let (jobs, compiled, stop) =
                Self::start_worker(&ctx, &sides[0].renderer, self.warm_device, self.wanted.clone());
            let lost = Arc::new(AtomicBool::new(false));
            Self::watch_device(&ctx, &lost, &self.gpu_error);
            self.timer = GpuTimer::new(&ctx, 3);
            let (warm_scene, warm) = Self::warm_renderer(&ctx)?;
            self.warm_scene = warm_scene;
            self.warm = warm;
            self.reference = None;
            self.ctx = ctx;
            self.gs = gs;
            self.sides = sides;
            self.display = display;
            self.jobs = jobs;
            self.compiled = compiled;
            self.worker_stop = stop;
            self.lost = lost;
            self.pipelines.clear();
            self.requested.clear();
            *self.gpu_error.lock().unwrap_or_else(|p| p.into_inner()) = None;
            self.request_pipelines();
            Ok(())
        })();
        match attempt {
            Ok(()) => {
                let n = self.recoveries;
                {
                    let mut s = self.shared();
                    s.recoveries = n;
                    s.has_reference = false;
                }
                self.message(format!("the GPU device was lost ({why}); recreated it and restarted the render"));
            }
            Err(e) => {
                self.shared().fatal = Some(format!("the GPU device was lost ({why}) and could not be recreated: {e}"));
                (self.repaint)();
            }
        }
    }

    /// Renders one engine frame: a bounded dispatch per active side, the display pass, the readback.
    /// Returns whether anything was rendered.
    fn frame(&mut self) -> Result<bool, GpuError> {
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
            }
        }
        let stats = !preview_frame && (full || self.last_stats.elapsed() >= STATS_INTERVAL);
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
