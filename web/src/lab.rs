//! The page's app: one built-in scene rendered progressively, the estimator switched from the panel.

use eframe::egui;
use mislab::gpu::types::GpuAccum;
use mislab::gpu::GpuContext;
use mislab::render::film::{Film, Tonemap};
use mislab::render::gpu_scene::GpuScene;
use mislab::render::scene_data::SceneData;
use mislab::render::settings::{Mode, Settings, Strategy};
use mislab::render::Renderer;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;
const SCENES: &[&str] = &["veach-mis", "cornell-box", "area-vs-cosine", "furnace", "many-lights"];
const STRATEGIES: &[Strategy] = &[Strategy::Uniform, Strategy::Cosine, Strategy::Bsdf, Strategy::Light, Strategy::Mis];

/// eframe's options: a WebGPU device with every feature and limit mislab uses that the adapter offers.
pub fn web_options() -> eframe::WebOptions {
    use eframe::egui_wgpu::{WgpuConfiguration, WgpuSetup, WgpuSetupCreateNew};
    let mut setup = WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = wgpu::Backends::BROWSER_WEBGPU;
    setup.device_descriptor = Arc::new(|adapter| {
        let (required_features, required_limits) = GpuContext::wanted(adapter);
        wgpu::DeviceDescriptor { label: Some("mislab"), required_features, required_limits, ..Default::default() }
    });
    let wgpu_options = WgpuConfiguration { wgpu_setup: WgpuSetup::CreateNew(setup), ..Default::default() };
    eframe::WebOptions { wgpu_options, ..Default::default() }
}

/// Writes a line the page shows under the canvas (and a test reads): `#status`.
pub fn report(line: &str) {
    #[cfg(target_arch = "wasm32")]
    if let Some(e) = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("status")) {
        e.set_text_content(Some(line));
    }
    #[cfg(not(target_arch = "wasm32"))]
    eprintln!("{line}");
}

/// The page address's query as (key, value) pairs.
fn page_query() -> Vec<(String, String)> {
    #[cfg(target_arch = "wasm32")]
    let search = web_sys::window().and_then(|w| w.location().search().ok()).unwrap_or_default();
    #[cfg(not(target_arch = "wasm32"))]
    let search = String::new();
    search
        .trim_start_matches('?')
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn strategy_name(s: Strategy) -> String {
    format!("{s:?}").to_lowercase()
}

/// A copy of the accumulators on its way to the CPU.
struct Readback {
    buffer: wgpu::Buffer,
    mapped: Arc<AtomicBool>,
    samples: u32,
}

pub struct WebLab {
    ctx: GpuContext,
    scene: usize,
    settings: Settings,
    renderer: Option<Renderer>,
    target_spp: u32,
    readback: Option<Readback>,
    image: Option<egui::TextureHandle>,
    shown: (u32, f64),
    error: Option<String>,
}

impl WebLab {
    pub fn new(cc: &eframe::CreationContext<'_>) -> Result<WebLab, String> {
        let rs = cc.wgpu_render_state.as_ref().ok_or("eframe started without wgpu")?;
        let ctx = GpuContext::from_device(rs.instance.clone(), rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
        let mut settings = Settings { width: WIDTH, height: HEIGHT, strategy: Strategy::Mis, ..Settings::default() };
        // The page's address may choose: ?scene=cornell-box&strategy=light&mode=path&spp=64 (a link to one view).
        let query = page_query();
        let get = |k: &str| query.iter().find(|(q, _)| q == k).map(|(_, v)| v.as_str());
        let scene = get("scene").and_then(|n| SCENES.iter().position(|s| *s == n)).unwrap_or(0);
        if let Some(s) = get("strategy").and_then(|v| STRATEGIES.iter().find(|s| strategy_name(**s) == v)) {
            settings.strategy = *s;
        }
        if get("mode") == Some("path") {
            settings.mode = Mode::Path;
        }
        let target_spp = get("spp").and_then(|v| v.parse().ok()).filter(|n| *n >= 1).unwrap_or(256);
        let mut lab = WebLab {
            ctx,
            scene,
            settings,
            renderer: None,
            target_spp,
            readback: None,
            image: None,
            shown: (0, 0.0),
            error: None,
        };
        lab.load_scene();
        Ok(lab)
    }

    fn load_scene(&mut self) {
        let name = SCENES[self.scene];
        let built = (|| -> Result<Renderer, String> {
            let scene = mislab::scene::load(name, &Default::default()).map_err(|e| e.to_string())?;
            let gs = GpuScene::upload(&self.ctx, SceneData::build(&scene)).map_err(|e| e.to_string())?;
            let mut r = Renderer::new_unprepared(&self.ctx, &gs, scene.camera.clone(), self.settings.clone())
                .map_err(|e| e.to_string())?;
            r.prepare().map_err(|e| e.to_string())?;
            Ok(r)
        })();
        self.readback = None;
        match built {
            Ok(r) => {
                self.renderer = Some(r);
                self.error = None;
            }
            Err(e) => {
                self.renderer = None;
                self.error = Some(format!("{name}: {e}"));
            }
        }
    }

    fn set_settings(&mut self, settings: Settings) {
        self.settings = settings;
        if let Some(r) = &mut self.renderer {
            if let Err(e) = r.set_settings(self.settings.clone()) {
                self.error = Some(e.to_string());
            }
        }
        self.readback = None;
    }

    /// One frame's GPU work: a sample per pixel and a copy of the accumulators; then, once mapped, the image.
    fn advance(&mut self, ui: &egui::Context) {
        let Some(r) = &mut self.renderer else { return };
        if let Some(rb) = &self.readback {
            if !rb.mapped.load(Ordering::Acquire) {
                return;
            }
            let accum: Vec<GpuAccum> = match rb.buffer.slice(..).get_mapped_range() {
                Ok(view) => bytemuck::pod_collect_to_vec(&view),
                Err(e) => {
                    self.error = Some(format!("reading the film: {e:?}"));
                    return;
                }
            };
            rb.buffer.unmap();
            let film = Film::from_accum(WIDTH, HEIGHT, &accum, 0);
            let rgb = film.to_rgb8(0.0, Tonemap::Clamp);
            let image = egui::ColorImage::from_rgb([WIDTH as usize, HEIGHT as usize], rgb.as_raw());
            match &mut self.image {
                Some(t) => t.set(image, egui::TextureOptions::NEAREST),
                None => self.image = Some(ui.load_texture("film", image, egui::TextureOptions::NEAREST)),
            }
            self.shown = (rb.samples, film.mean_value());
            self.readback = None;
        }
        if r.samples() >= self.target_spp && self.shown.0 >= self.target_spp {
            return;
        }
        let device = &self.ctx.device;
        let mut enc = device.create_command_encoder(&Default::default());
        if r.samples() < self.target_spp {
            r.record(&mut enc, 1, None);
        }
        let bytes = (WIDTH * HEIGHT) as u64 * std::mem::size_of::<GpuAccum>() as u64;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("film readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        enc.copy_buffer_to_buffer(r.accum_buffer(), 0, &buffer, 0, bytes);
        self.ctx.queue.submit([enc.finish()]);
        let mapped = Arc::new(AtomicBool::new(false));
        let flag = mapped.clone();
        buffer.slice(..).map_async(wgpu::MapMode::Read, move |result| flag.store(result.is_ok(), Ordering::Release));
        self.readback = Some(Readback { buffer, mapped, samples: r.samples() });
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("mislab");
        ui.label("Monte Carlo estimators, live, on WebGPU");
        ui.separator();
        let mut scene = self.scene;
        egui::ComboBox::from_label("scene").selected_text(SCENES[scene]).show_ui(ui, |ui| {
            for (i, name) in SCENES.iter().enumerate() {
                ui.selectable_value(&mut scene, i, *name);
            }
        });
        if scene != self.scene {
            self.scene = scene;
            self.load_scene();
        }
        let mut s = self.settings.clone();
        ui.label("directions for direct light:");
        for strategy in STRATEGIES {
            ui.radio_value(&mut s.strategy, *strategy, strategy_name(*strategy));
        }
        ui.horizontal(|ui| {
            ui.radio_value(&mut s.mode, Mode::Direct, "direct");
            ui.radio_value(&mut s.mode, Mode::Path, "path");
        });
        if s != self.settings {
            self.set_settings(s);
        }
        ui.add(egui::Slider::new(&mut self.target_spp, 1..=4096).logarithmic(true).text("spp"));
        ui.separator();
        let info = &self.ctx.info;
        ui.label(format!("{} ({:?})", info.name, info.backend));
        if let Some(r) = &self.renderer {
            ui.label(format!("{} spp, mean {:.4}", self.shown.0, self.shown.1));
            ui.label(if r.features().packed_scene { "scene tables: packed" } else { "scene tables: separate" });
        }
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::RED, e);
        }
    }
}

impl eframe::App for WebLab {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.advance(&ctx);
        egui::Panel::left("mislab-panel").default_size(220.0).resizable(false).show(ui, |ui| self.panel(ui));
        egui::CentralPanel::default().show(ui, |ui| {
            if let Some(t) = &self.image {
                ui.image((t.id(), egui::vec2(WIDTH as f32, HEIGHT as f32) * 2.0));
            }
        });
        let strategy = strategy_name(self.settings.strategy);
        report(&match &self.error {
            Some(e) => format!("error: {e}"),
            None => format!(
                "scene={} strategy={strategy} spp={} mean={:.6}",
                SCENES[self.scene], self.shown.0, self.shown.1
            ),
        });
        ctx.request_repaint();
    }
}
