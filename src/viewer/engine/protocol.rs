//! The engine's thread protocol: what the UI sends ([`Command`]), what the two threads share ([`Shared`],
//! [`Frame`], [`SideStats`]), what the engine starts with ([`EngineConfig`]) and the UI's handle on the
//! thread ([`EngineHandle`], made by [`spawn`]).

use super::Engine;
use crate::gpu::GpuContext;
use crate::render::display::ImageStats;
use crate::render::display::View;
use crate::render::film::Tonemap;
use crate::render::settings::{EnvSampling, Settings};
use crate::scene::{Camera, Scene};
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

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
    /// How the renderer samples the environment: `settings.env_sampling` with `auto` resolved (`sky_probe`).
    pub env_sampling: EnvSampling,
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
            shared.lock().unwrap_or_else(|p| p.into_inner()).fatal = Some(e.to_string());
            repaint();
            return;
        }
    };
    engine.run(rx);
}
