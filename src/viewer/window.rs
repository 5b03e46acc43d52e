//! `mislab view` as a command: its arguments, the scene and engine it starts, and the native window it opens.

use super::app::Viewer;
use super::{engine, ViewerError};
use crate::gpu::GpuContext;
use crate::render::display::View;
use crate::render::film::Tonemap;
use crate::render::settings::{Settings, Strategy};
use crate::scene::{Scene, SceneSpec};
use eframe::{egui, egui_wgpu};
use engine::{DisplayOptions, EngineConfig};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Command-line arguments of `mislab view`.
#[derive(clap::Args, Clone, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneSpec,
    /// Film width in pixels.
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    /// Film height in pixels.
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    /// A reference EXR of the film's size (for RMSE and the relmse view).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Estimator of side A (the other settings start at the CLI defaults; change them in the panel).
    #[arg(long, value_enum, default_value_t = Strategy::Mis)]
    pub strategy: Strategy,
    /// Start with a split-screen comparison whose side B uses this strategy.
    #[arg(long, value_enum)]
    pub compare: Option<Strategy>,
    /// What is shown: image, std-error (the standard error of each pixel's mean, false colour), relmse (against
    /// --reference) or nan-inf.
    #[arg(long, default_value = "image", value_parser = parse_view)]
    pub view: View,
    /// Tonemapper.
    #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
    pub tonemap: Tonemap,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Save a screenshot of the whole window (panel included) to this PNG after --frames render
    /// frames, then exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Render frames (bounded-time dispatches) before the screenshot; it also waits for a whole sample per pixel.
    #[arg(long, default_value_t = 30)]
    pub frames: u64,
    /// With --screenshot: first toggle side A's strategy this many times (cycling through every
    /// strategy, one toggle every 1.5 s) and print how long each took to show the new estimator.
    #[arg(long, default_value_t = 0)]
    pub toggles: u32,
    /// Experimental: compile each pipeline on a second device first, hoping Mesa's shader cache spares
    /// the render device the compile (it did not in our measurements; see docs/viewer.md).
    #[arg(long, hide = true)]
    pub warm_device: bool,
    /// Never build the generic pipeline (a toggle then waits for its specialised pipeline).
    #[arg(long, hide = true)]
    pub no_generic: bool,
}

fn parse_view(s: &str) -> Result<View, String> {
    // The old name, kept working for scripts.
    let s = if s == "stderr" { "std-error" } else { s };
    View::ALL.iter().copied().find(|v| v.name() == s).ok_or_else(|| {
        format!(
            "unknown view '{s}' (expected one of: {})",
            View::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", ")
        )
    })
}

impl Default for ViewArgs {
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Wrapper {
            #[command(flatten)]
            args: ViewArgs,
        }
        <Wrapper as clap::Parser>::parse_from(["view"]).args
    }
}

/// Loads the scene (see `SceneSpec::load`).
pub fn load_scene(args: &ViewArgs) -> Result<Scene, ViewerError> {
    Ok(args.scene.load(crate::gpu::chosen_adapter_storage_limit())?)
}

/// The engine configuration and the panel's starting state for `args`.
pub fn config(args: &ViewArgs, scene: Scene) -> Result<(EngineConfig, [Settings; 2], DisplayOptions), ViewerError> {
    let a = Settings {
        width: args.width,
        height: args.height,
        strategy: args.strategy,
        exposure: args.exposure,
        ..Settings::default()
    };
    a.validate()?;
    let b = Settings { strategy: args.compare.unwrap_or(Strategy::Bsdf), ..a.clone() };
    let display =
        DisplayOptions { view: args.view, tonemap: args.tonemap, exposure: args.exposure, ..DisplayOptions::default() };
    let settings = [a, b];
    let config = EngineConfig {
        scene,
        scene_name: args.scene.scene.clone(),
        settings: settings.clone(),
        compare: args.compare.is_some(),
        display,
        warm_device: args.warm_device,
        generic: !args.no_generic,
    };
    Ok((config, settings, display))
}

/// A viewer (UI state + engine thread) on a render device of its own, as the window and the tests use it.
pub fn start(args: &ViewArgs, repaint: Arc<dyn Fn() + Send + Sync>) -> Result<Viewer, ViewerError> {
    let scene = load_scene(args)?;
    let (config, settings, display) = config(args, scene)?;
    let ctx = GpuContext::new().map_err(ViewerError::from)?;
    let compare = config.compare;
    let engine = engine::spawn(ctx, config, repaint);
    if let Some(r) = &args.reference {
        engine.send(engine::Command::LoadReference(r.clone()));
    }
    let mut v = Viewer::new(engine, settings, compare, display, args.scene.scene.clone());
    if let Some(r) = &args.reference {
        v.reference_path = r.display().to_string();
    }
    Ok(v)
}

/// What the screenshot mode is doing.
struct Screenshot {
    path: PathBuf,
    frames: u64,
    toggles_left: u32,
    next_toggle: Option<Instant>,
    started: Instant,
    frames_at_toggles_end: Option<u64>,
    requested: bool,
    saved: Arc<Mutex<Option<Result<(), String>>>>,
    rendering_since: Option<Instant>,
    /// The frame count when every rendered side first had a whole sample per pixel (after the toggles).
    sampled_at: Option<u64>,
}

/// How the window ended.
type Outcome = Arc<Mutex<Option<Result<(), String>>>>;

struct App {
    viewer: Viewer,
    /// CPU seconds eframe measured for each UI frame (building + painting).
    ui_cpu: Vec<f64>,
    shot: Option<Screenshot>,
    outcome: Outcome,
}

/// Longest a --screenshot run may take (a cold shader cache costs about a minute on lavapipe).
const SCREENSHOT_TIMEOUT: Duration = Duration::from_secs(540);

impl App {
    fn finish(&self, ctx: &egui::Context, r: Result<(), String>) {
        *self.outcome.lock().unwrap_or_else(|p| p.into_inner()) = Some(r);
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }

    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let Some(shot) = &mut self.shot else { return };
        ctx.request_repaint();
        let (frames, fatal, compiling, sampled) = {
            let s = self.viewer.engine().shared();
            // Every rendered side has a whole sample per pixel: frames are time-bounded bands, so at 512² the
            // first frames are all parts of the first pass (the window said "0 spp").
            let sides = if s.compare { 2 } else { 1 };
            let sampled = s.stats.iter().take(sides).all(|st| st.spp >= 1 && st.shown);
            (s.frames, s.fatal.clone(), s.compiling, sampled)
        };
        if let Some(f) = fatal {
            return self.finish(ctx, Err(f));
        }
        if shot.started.elapsed() > SCREENSHOT_TIMEOUT {
            let msg = format!(
                "--screenshot: only {frames} of {} frames after {} s",
                shot.frames,
                SCREENSHOT_TIMEOUT.as_secs()
            );
            return self.finish(ctx, Err(msg));
        }
        if frames > 0 && shot.rendering_since.is_none() {
            shot.rendering_since = Some(Instant::now());
            self.viewer.frame_intervals.clear();
        }
        // Strategy toggles (once every pipeline asked for so far is built, so the generic one is there).
        if shot.toggles_left > 0 {
            if frames == 0 || compiling > 0 && shot.next_toggle.is_none() {
                return;
            }
            let now = Instant::now();
            let due = shot.next_toggle.is_none_or(|t| now >= t);
            if due {
                let all = Strategy::ALL;
                let cur = all.iter().position(|s| *s == self.viewer.settings[0].strategy).unwrap_or(0);
                self.viewer.settings[0].strategy = all[(cur + 1) % all.len()];
                self.viewer.apply_settings(0);
                shot.toggles_left -= 1;
                shot.next_toggle = Some(now + Duration::from_millis(1500));
            }
            return;
        }
        if let Some(t) = shot.next_toggle {
            if Instant::now() < t {
                return;
            }
        }
        let base = *shot.frames_at_toggles_end.get_or_insert(frames);
        let shown = self.viewer.frame().map(|f| f.serial).unwrap_or(0);
        if sampled && shot.sampled_at.is_none() {
            shot.sampled_at = Some(frames);
        }
        // A frame finished after the first whole pass shows it.
        let shows_samples = shot.sampled_at.is_some_and(|f| shown > f);
        if !shot.requested && frames >= base + shot.frames && shown >= base + shot.frames && shows_samples {
            shot.requested = true;
            let path = shot.path.clone();
            let saved = shot.saved.clone();
            let ctx2 = ctx.clone();
            ctx.request_screenshot(move |image| {
                let [w, h] = image.size;
                let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
                let r = match image::RgbaImage::from_raw(w as u32, h as u32, bytes) {
                    Some(img) => image::DynamicImage::ImageRgba8(img)
                        .to_rgb8()
                        .save(&path)
                        .map_err(|e| format!("{}: {e}", path.display())),
                    None => Err("the screenshot has an unexpected size".into()),
                };
                *saved.lock().unwrap_or_else(|p| p.into_inner()) = Some(r);
                ctx2.request_repaint();
            });
        }
        let saved = shot.saved.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(r) = saved {
            self.report();
            let path = self.shot.as_ref().map(|s| s.path.display().to_string()).unwrap_or_default();
            if r.is_ok() {
                let spp = self.viewer.engine().shared().stats[0].spp;
                eprintln!("wrote {path} ({spp} spp on side A)");
            }
            self.finish(ctx, r);
        }
    }

    /// Prints what the screenshot run measured: UI frame rate while rendering, toggle latencies.
    fn report(&self) {
        let mut iv: Vec<f64> = self.viewer.frame_intervals.iter().copied().collect();
        if !iv.is_empty() {
            iv.sort_by(|a, b| a.total_cmp(b));
            let mean = iv.iter().sum::<f64>() / iv.len() as f64;
            let q = |p: f64| iv[((iv.len() - 1) as f64 * p).round() as usize] * 1e3;
            eprintln!(
                "UI while rendering: {} frames, {:.1} frames/s on average; frame interval median {:.1} ms, 95th percentile {:.1} ms, max {:.1} ms",
                iv.len(),
                1.0 / mean,
                q(0.5),
                q(0.95),
                q(1.0)
            );
        }
        if !self.ui_cpu.is_empty() {
            let mut c = self.ui_cpu.clone();
            c.sort_by(|a, b| a.total_cmp(b));
            eprintln!(
                "UI frame CPU time (eframe): median {:.1} ms, max {:.1} ms",
                c[c.len() / 2] * 1e3,
                c[c.len() - 1] * 1e3
            );
        }
        let lat = &self.viewer.toggle_latencies_ms;
        if !lat.is_empty() {
            let mut s = lat.clone();
            s.sort_by(|a, b| a.total_cmp(b));
            eprintln!(
                "toggle → first image of the new estimator: {} toggles, median {:.0} ms, max {:.0} ms ({})",
                s.len(),
                s[s.len() / 2],
                s[s.len() - 1],
                lat.iter().map(|x| format!("{x:.0}")).collect::<Vec<_>>().join(", ")
            );
        }
        let s = self.viewer.engine().shared();
        for (i, st) in s.stats.iter().enumerate().take(if s.compare { 2 } else { 1 }) {
            eprintln!(
                "side {}: {} · {} spp · {:.2} M samples/s · {:.2} Mrays/s · {:.1} GPU ms/dispatch · {:?}",
                if i == 0 { "A" } else { "B" },
                st.settings.strategy,
                st.spp,
                st.samples_per_s / 1e6,
                st.mrays_per_s,
                st.gpu_ms,
                st.pipeline
            );
        }
    }
}

impl eframe::App for App {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        if let Some(cpu) = frame.info().cpu_usage {
            self.viewer.set_ui_cost(cpu as f64);
            self.ui_cpu.push(cpu as f64);
        }
        self.viewer.ui(ui);
        let ctx = ui.ctx().clone();
        self.screenshot_step(&ctx);
    }
}

/// Opens the viewer window and runs it until it is closed (or, with --screenshot, until the
/// screenshot is written). Errors: the scene or device could not be opened, the window could not be
/// created, or the renderer stopped (device lost for good).
pub fn run(args: ViewArgs) -> Result<(), ViewerError> {
    if let Some(p) = &args.screenshot {
        let ext = p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
        if ext.as_deref() != Some("png") {
            return Err(ViewerError::Input(format!("{}: --screenshot writes PNG (use a .png name)", p.display())));
        }
    }
    // Fail before opening a window when the scene or the device is missing.
    let scene = load_scene(&args)?;
    let (_, _, _) = config(&args, scene)?;
    let width = super::app::PANEL_WIDTH + 24.0 + args.width as f32;
    let height = (args.height as f32 + 20.0).max(760.0);
    crate::gpu::prepare_driver_environment();
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = wgpu::Backends::VULKAN;
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(format!("mislab view — {}", args.scene.scene))
            .with_inner_size([width, height]),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: egui_wgpu::WgpuSetup::CreateNew(setup),
            // Without vsync: on a software rasterizer a frame should be shown as soon as it is drawn.
            surface: egui_wgpu::SurfaceConfig {
                present_mode: wgpu::PresentMode::AutoNoVsync,
                desired_maximum_frame_latency: Some(1),
            },
            ..Default::default()
        },
        ..Default::default()
    };
    let outcome: Outcome = Arc::new(Mutex::new(None));
    let outcome2 = outcome.clone();
    let startup_error: Arc<Mutex<Option<ViewerError>>> = Arc::new(Mutex::new(None));
    let startup_error2 = startup_error.clone();
    let result = eframe::run_native(
        "mislab view",
        options,
        Box::new(move |cc| {
            let ctx = cc.egui_ctx.clone();
            let viewer = match start(&args, Arc::new(move || ctx.request_repaint())) {
                Ok(v) => v,
                Err(e) => {
                    *startup_error2.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                    return Err("the viewer could not start".into());
                }
            };
            let shot = args.screenshot.clone().map(|path| Screenshot {
                path,
                frames: args.frames.max(1),
                toggles_left: args.toggles,
                next_toggle: None,
                started: Instant::now(),
                frames_at_toggles_end: None,
                requested: false,
                saved: Arc::new(Mutex::new(None)),
                rendering_since: None,
                sampled_at: None,
            });
            Ok(Box::new(App { viewer, ui_cpu: Vec::new(), shot, outcome: outcome2 }))
        }),
    );
    if let Some(e) = startup_error.lock().unwrap_or_else(|p| p.into_inner()).take() {
        return Err(e);
    }
    result.map_err(|e| ViewerError::Input(format!("could not open the viewer window: {e}")))?;
    let outcome = outcome.lock().unwrap_or_else(|p| p.into_inner()).take();
    outcome.unwrap_or(Ok(())).map_err(ViewerError::Input)
}
