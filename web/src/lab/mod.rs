//! The page's app: a scene (built in, or files dropped on the page or opened from it) rendered progressively by
//! one renderer, or two side by side (A | B, the split dragged across the image), through the viewer's display
//! pass (image, standard error, relMSE against a dropped reference, NaN/Inf); every estimator setting in the
//! viewer's panel; the image saved as PNG or EXR by a download.
//!
//! Nothing here blocks (a browser cannot wait on its GPU): each frame records a sample per pixel on each side
//! (at most two submissions in flight), and, when no readback is on its way, the display pass and copies of the
//! accumulators, mapped asynchronously; a later frame, once the browser has mapped them, shows the image.

mod panel;

use crate::files::{self, BatchUse, FileSet, Inbox};
use crate::page;
use eframe::egui;
use mislab::gpu::types::GpuAccum;
use mislab::gpu::GpuContext;
use mislab::render::display::{self, DisplayInputs, DisplayParams, DisplayPass, ImageStats, View};
use mislab::render::film::{Film, Tonemap};
use mislab::render::gpu_scene::GpuScene;
use mislab::render::scene_data::SceneData;
use mislab::render::settings::{EnvSampling, Mode, Settings, Strategy};
use mislab::render::Renderer;
use mislab::scene::{Camera, LoadOptions};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;

/// The built-in scenes the page offers.
pub const BUILTINS: &[&str] = &["veach-mis", "cornell-box", "area-vs-cosine", "furnace", "many-lights"];
/// The strategies of the lecture, as quick toggles above the full panel.
const STRATEGIES: &[Strategy] = &[Strategy::Uniform, Strategy::Cosine, Strategy::Bsdf, Strategy::Light, Strategy::Mis];
/// Submissions the page lets the GPU queue hold before it waits for one to finish.
const MAX_IN_FLIGHT: u32 = 2;

/// Where the scene comes from.
enum Source {
    Builtin(usize),
    Files { set: FileSet, main: usize },
}

/// A copy of the display image and the accumulators on its way to the CPU.
struct Readback {
    /// Mapping callbacks still to come.
    waiting: Arc<AtomicU32>,
    failed: Arc<AtomicBool>,
    samples: [u32; 2],
    sides: usize,
    /// The renderers restarted after it was recorded: it is unmapped and dropped once it arrives (a buffer being
    /// mapped may not be used by a submission, so a readback is never abandoned in flight).
    stale: bool,
}

/// What the image area shows now.
#[derive(Default)]
struct Shown {
    spp: [u32; 2],
    mean: [f64; 2],
    stats: [ImageStats; 2],
    /// Side A's accumulators (the download's image).
    accum_a: Vec<GpuAccum>,
}

/// Pixel samples per second since the first image after a restart.
#[derive(Default)]
struct Rate {
    first: Option<(f64, u64)>,
    per_s: f64,
}

pub struct WebLab {
    ctx: GpuContext,
    width: u32,
    height: u32,
    source: Source,
    scene_name: String,
    scene: Option<(GpuScene, Camera)>,
    settings: [Settings; 2],
    compare: bool,
    sides: Vec<Renderer>,
    display: DisplayPass,
    accum_copies: [wgpu::Buffer; 2],
    view: View,
    tonemap: Tonemap,
    exposure: f32,
    split: f32,
    log_range: [f32; 2],
    reference: Option<wgpu::Buffer>,
    target_spp: u32,
    readback: Option<Readback>,
    in_flight: Arc<AtomicU32>,
    display_dirty: bool,
    image: Option<egui::TextureHandle>,
    shown: Shown,
    rate: Rate,
    inbox: Inbox,
    notes: Vec<String>,
    error: Option<String>,
    controls: Vec<(String, egui::Rect)>,
    /// Frames the page has drawn, and when the last one began (the status line's frame time).
    frames: u64,
    frame_ms: f64,
    last_frame_s: f64,
}

impl WebLab {
    pub fn new(cc: &eframe::CreationContext<'_>) -> Result<WebLab, String> {
        let rs = cc.wgpu_render_state.as_ref().ok_or("eframe started without wgpu")?;
        let ctx = GpuContext::from_device(rs.instance.clone(), rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
        // The page's address may choose: ?scene=cornell-box&strategy=light&compare=bsdf&mode=path&spp=64&width=320
        let query = page::query();
        let get = |k: &str| query.iter().find(|(q, _)| q == k).map(|(_, v)| v.as_str());
        let size =
            |k: &str, d: u32| get(k).and_then(|v| v.parse().ok()).filter(|n| (16..=1920).contains(n)).unwrap_or(d);
        let (width, height) = (size("width", 320), size("height", 240));
        let mut a = Settings { width, height, strategy: Strategy::Mis, ..Settings::default() };
        if let Some(s) = get("strategy").and_then(|v| STRATEGIES.iter().find(|s| s.name() == v)) {
            a.strategy = *s;
        }
        if get("mode") == Some("path") {
            a.mode = Mode::Path;
        }
        let mut b = Settings { strategy: Strategy::Bsdf, ..a.clone() };
        let compare = match get("compare").and_then(|v| STRATEGIES.iter().find(|s| s.name() == v)) {
            Some(s) => {
                b.strategy = *s;
                true
            }
            None => false,
        };
        let scene = get("scene").and_then(|n| BUILTINS.iter().position(|s| *s == n)).unwrap_or(0);
        let target_spp = get("spp").and_then(|v| v.parse().ok()).filter(|n| *n >= 1).unwrap_or(256);
        let display = DisplayPass::new(&ctx, width, height).map_err(|e| e.to_string())?;
        let copy = |label: &str| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: width as u64 * height as u64 * std::mem::size_of::<GpuAccum>() as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let accum_copies = [copy("accumulators A"), copy("accumulators B")];
        let mut lab = WebLab {
            ctx,
            width,
            height,
            source: Source::Builtin(scene),
            scene_name: String::new(),
            scene: None,
            settings: [a, b],
            compare,
            sides: Vec::new(),
            display,
            accum_copies,
            view: View::Image,
            tonemap: Tonemap::Clamp,
            exposure: 0.0,
            split: 0.5,
            log_range: [-4.0, 0.0],
            reference: None,
            target_spp,
            readback: None,
            in_flight: Arc::new(AtomicU32::new(0)),
            display_dirty: true,
            image: None,
            shown: Shown::default(),
            rate: Rate::default(),
            inbox: Inbox::default(),
            notes: Vec::new(),
            error: None,
            controls: Vec::new(),
            frames: 0,
            frame_ms: 0.0,
            last_frame_s: page::now_s(),
        };
        lab.load_scene();
        Ok(lab)
    }

    /// Loads the scene of `self.source` and builds the sides' renderers for it.
    fn load_scene(&mut self) {
        let options = LoadOptions::default();
        let (name, loaded) = match &self.source {
            Source::Builtin(i) => (BUILTINS[*i].to_string(), mislab::scene::load(BUILTINS[*i], &options)),
            Source::Files { set, main } => {
                let name = set.scenes[*main].clone();
                let loaded = mislab::scene::load_from_files(&name, &set.files, &options);
                (name, loaded)
            }
        };
        self.scene_name = name;
        self.sides.clear();
        self.scene = None;
        self.reference = None;
        self.forget_image();
        let scene = match loaded {
            Ok(s) => s,
            Err(e) => return self.error = Some(e.to_string()),
        };
        self.notes = scene.warnings.clone();
        // What the file says of its rendering (a Mitsuba <integrator type="path">, pbrt's Integrator, a filter or
        // sampler) becomes both sides' settings, as `mislab render` takes it; the panel changes them after.
        for s in &mut self.settings {
            let taken = mislab::api::take_file_settings(s, &scene.file_settings, &|_| false, None);
            for note in taken {
                if !self.notes.contains(&note) {
                    self.notes.push(note);
                }
            }
        }
        match GpuScene::upload(&self.ctx, SceneData::build(&scene)) {
            Ok(gs) => self.scene = Some((gs, scene.camera.clone())),
            Err(e) => return self.error = Some(format!("{}: {e}", self.scene_name)),
        }
        self.error = None;
        self.build_sides();
    }

    /// (Re)builds the renderers: side A, and B when comparing.
    fn build_sides(&mut self) {
        self.sides.clear();
        self.forget_image();
        let Some((gs, camera)) = &self.scene else { return };
        for i in 0..1 + self.compare as usize {
            let built = Renderer::new_unprepared(&self.ctx, gs, camera.clone(), self.settings[i].clone())
                .and_then(|mut r| r.prepare().map(|()| r));
            match built {
                Ok(r) => self.sides.push(r),
                Err(e) => {
                    self.error = Some(e.to_string());
                    self.sides.clear();
                    return;
                }
            }
        }
        for i in 0..self.sides.len() {
            self.without_blocking_guide(i);
        }
    }

    /// The environment guide learns from a readback the renderer waits for, which a page cannot: a constant
    /// environment is sampled by importance (the cosine) on the page instead of guided.
    fn without_blocking_guide(&mut self, i: usize) {
        if self.sides[i].wants_guide() {
            self.settings[i].env_sampling = EnvSampling::Importance;
            if let Err(e) = self.sides[i].set_settings(self.settings[i].clone()) {
                self.error = Some(e.to_string());
            }
            let note = "env-sampling guided needs a blocking readback: the page samples by importance".to_string();
            if !self.notes.contains(&note) {
                self.notes.push(note);
            }
        }
    }

    /// The image shown no longer matches the renderers (a restart): nothing shown until the next readback.
    fn forget_image(&mut self) {
        self.readback_stale();
        self.shown = Shown::default();
        self.rate = Rate::default();
        self.display_dirty = true;
    }

    fn readback_stale(&mut self) {
        if let Some(rb) = &mut self.readback {
            rb.stale = true;
        }
    }

    fn set_settings(&mut self, i: usize) {
        if let Some(r) = self.sides.get_mut(i) {
            if let Err(e) = r.set_settings(self.settings[i].clone()) {
                self.error = Some(e.to_string());
            } else {
                self.error = None;
            }
            self.without_blocking_guide(i);
        }
        self.readback_stale();
        self.shown.spp[i] = 0;
        self.rate = Rate::default();
        self.display_dirty = true;
    }

    /// Files that arrived: a new scene, more files for this one, or a reference.
    fn take_files(&mut self) {
        for batch in self.inbox.take() {
            match files::classify(batch) {
                BatchUse::NewScene(set) => {
                    self.source = Source::Files { set, main: 0 };
                    self.load_scene();
                }
                BatchUse::More(more) => {
                    if let Source::Files { set, .. } = &mut self.source {
                        for a in more {
                            set.files.insert(&a.name, a.bytes);
                        }
                        self.load_scene();
                    } else {
                        self.error = Some("drop a scene file (.gltf .glb .toml .pbrt .xml) with its files".into());
                    }
                }
                BatchUse::Reference(a) => match display::decode_reference(&a.bytes, self.width, self.height) {
                    Ok(rgb) => {
                        self.reference = Some(display::upload_reference(&self.ctx, &rgb));
                        self.view = View::RelMse;
                        self.display_dirty = true;
                    }
                    Err(e) => self.error = Some(format!("{}: {e}", a.name)),
                },
            }
        }
    }

    /// One frame's GPU work (see the module's comment).
    fn advance(&mut self, ui: &egui::Context) {
        self.take_files();
        self.finish_readback(ui);
        if self.sides.is_empty() {
            return;
        }
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
        let mut recorded = false;
        if self.in_flight.load(Ordering::Acquire) < MAX_IN_FLIGHT {
            for r in &mut self.sides {
                if r.samples() < self.target_spp {
                    r.record(&mut enc, 1, None);
                    recorded = true;
                }
            }
        }
        let behind = self.sides.iter().enumerate().any(|(i, r)| r.samples() != self.shown.spp[i]);
        let read = self.readback.is_none() && (behind || self.display_dirty);
        if read {
            self.encode_readback(&mut enc);
        }
        if !recorded && !read {
            return;
        }
        self.ctx.queue.submit([enc.finish()]);
        self.in_flight.fetch_add(1, Ordering::AcqRel);
        let in_flight = self.in_flight.clone();
        self.ctx.queue.on_submitted_work_done(move || {
            in_flight.fetch_sub(1, Ordering::AcqRel);
        });
        if read {
            self.map_readback();
        }
    }

    fn display_params(&self) -> DisplayParams {
        let (w, h) = (self.width, self.height);
        let compare = self.sides.len() == 2;
        DisplayParams {
            width: w,
            height: h,
            view: self.view.tag(),
            tonemap: display::tonemap_tag(self.tonemap),
            exposure_scale: self.exposure.exp2(),
            split_x: if compare { (self.split.clamp(0.0, 1.0) * w as f32).round() as u32 } else { w },
            compare: compare as u32,
            has_reference: self.reference.is_some() as u32,
            preview_scale: 1,
            preview_width: w,
            preview_height: h,
            log_min: self.log_range[0],
            log_max: self.log_range[1],
            row_offset: 0,
            row_count: h,
            ..Default::default()
        }
    }

    /// Records the display pass and the copies of the accumulators (read back by `map_readback`).
    fn encode_readback(&mut self, enc: &mut wgpu::CommandEncoder) {
        let b = self.sides.len() - 1;
        let accum = [self.sides[0].accum_buffer(), self.sides[b].accum_buffer()];
        let inputs = DisplayInputs { accum, preview: accum, reference: self.reference.as_ref() };
        self.display.encode(enc, &self.display_params(), &inputs, true, None);
        for (side, copy) in self.sides.iter().zip(&self.accum_copies) {
            enc.copy_buffer_to_buffer(side.accum_buffer(), 0, copy, 0, copy.size());
        }
        self.readback = Some(Readback {
            waiting: Arc::new(AtomicU32::new(0)),
            failed: Arc::new(AtomicBool::new(false)),
            samples: [self.sides[0].samples(), self.sides[b].samples()],
            sides: self.sides.len(),
            stale: false,
        });
        self.display_dirty = false;
    }

    fn map_readback(&self) {
        let Some(rb) = &self.readback else { return };
        let buffers = std::iter::once(self.display.staging()).chain(self.accum_copies.iter().take(rb.sides));
        for buffer in buffers {
            rb.waiting.fetch_add(1, Ordering::AcqRel);
            let (waiting, failed) = (rb.waiting.clone(), rb.failed.clone());
            buffer.map_async(wgpu::MapMode::Read, .., move |result| {
                if result.is_err() {
                    failed.store(true, Ordering::Release);
                }
                waiting.fetch_sub(1, Ordering::AcqRel);
            });
        }
    }

    /// Once the browser has mapped a readback: the image, the statistics and the means.
    fn finish_readback(&mut self, ui: &egui::Context) {
        let Some(rb) = &self.readback else { return };
        if rb.waiting.load(Ordering::Acquire) > 0 {
            return;
        }
        let rb = self.readback.take().unwrap();
        if rb.failed.load(Ordering::Acquire) {
            self.error = Some("the browser could not map the image for reading".into());
            return;
        }
        if rb.stale {
            self.display.staging().unmap();
            for copy in self.accum_copies.iter().take(rb.sides) {
                copy.unmap();
            }
            return;
        }
        let out = match self.display.read_mapped(true) {
            Ok(out) => out,
            Err(e) => return self.error = Some(e.to_string()),
        };
        for i in 0..rb.sides {
            let copy = &self.accum_copies[i];
            let accum: Vec<GpuAccum> = match copy.slice(..).get_mapped_range() {
                Ok(view) => bytemuck::pod_collect_to_vec(&view),
                Err(e) => return self.error = Some(format!("reading the film: {e:?}")),
            };
            copy.unmap();
            let film = Film::from_accum(self.width, self.height, &accum, 0);
            self.shown.mean[i] = film.mean_value();
            self.shown.spp[i] = rb.samples[i];
            if i == 0 {
                self.shown.accum_a = accum;
            }
        }
        if rb.sides == 1 {
            self.shown.spp[1] = rb.samples[0];
            self.shown.mean[1] = self.shown.mean[0];
        }
        self.shown.stats = out.stats.unwrap_or_default();
        let image = egui::ColorImage::from_rgba_unmultiplied([self.width as usize, self.height as usize], &out.rgba);
        match &mut self.image {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.image = Some(ui.load_texture("film", image, egui::TextureOptions::NEAREST)),
        }
        // Samples per second of the whole page (both sides), from the first image after a restart.
        let pixel_samples: u64 =
            rb.samples[..rb.sides].iter().map(|s| *s as u64).sum::<u64>() * self.width as u64 * self.height as u64;
        let now = page::now_s();
        match self.rate.first {
            None => self.rate.first = Some((now, pixel_samples)),
            Some((t0, n0)) if now > t0 && pixel_samples > n0 => {
                self.rate.per_s = (pixel_samples - n0) as f64 / (now - t0);
            }
            Some(_) => {}
        }
    }

    /// Side A's image as a PNG or EXR download.
    fn save(&mut self, format: &str) {
        if self.shown.accum_a.is_empty() {
            return;
        }
        let film = Film::from_accum(self.width, self.height, &self.shown.accum_a, 0);
        let s = &self.settings[0];
        let attributes = [
            ("scene".to_string(), self.scene_name.clone()),
            ("strategy".to_string(), s.strategy.name().to_string()),
            ("mode".to_string(), s.mode.name().to_string()),
            ("spp".to_string(), self.shown.spp[0].to_string()),
            ("seed".to_string(), s.seed.to_string()),
        ];
        let stem = self.scene_name.rsplit_once('.').map_or(self.scene_name.as_str(), |(s, _)| s);
        let name = format!("{stem}-{}-{}spp.{format}", s.strategy.name(), self.shown.spp[0]);
        let mime = if format == "png" { "image/png" } else { "image/x-exr" };
        if let Err(e) = film
            .encoded(format, self.exposure, self.tonemap, &attributes)
            .and_then(|bytes| files::download(&name, &bytes, mime))
        {
            self.error = Some(format!("saving {name}: {e}"));
        }
    }

    /// The status line a test reads.
    fn status(&self) -> String {
        if let Some(e) = &self.error {
            return format!("error: {e}");
        }
        let mut line = format!(
            "scene={} strategy={} spp={} mean={:.6}",
            self.scene_name,
            self.settings[0].strategy.name(),
            self.shown.spp[0],
            self.shown.mean[0]
        );
        if self.sides.len() == 2 {
            line += &format!(
                " strategy_b={} spp_b={} mean_b={:.6}",
                self.settings[1].strategy.name(),
                self.shown.spp[1],
                self.shown.mean[1]
            );
        }
        line += &format!(
            " mode={} view={} nonfinite_px={} samples_per_s={:.0} frames={} frame_ms={:.0}",
            self.settings[0].mode.name(),
            self.view.name(),
            self.shown.stats[0].nonfinite_px,
            self.rate.per_s,
            self.frames,
            self.frame_ms
        );
        line
    }
}

impl eframe::App for WebLab {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let now = page::now_s();
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * (now - self.last_frame_s) * 1e3;
        (self.frames, self.last_frame_s) = (self.frames + 1, now);
        self.inbox.accept_dropped(ctx.input(|i| i.raw.dropped_files.clone()));
        self.advance(&ctx);
        self.controls.clear();
        egui::Panel::left("mislab-panel").default_size(290.0).resizable(false).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.image_area(ui));
        if ctx.input(|i| !i.raw.hovered_files.is_empty()) {
            let screen = ctx.content_rect();
            let painter = ctx.layer_painter(egui::LayerId::new(egui::Order::Foreground, egui::Id::unique("drop")));
            painter.rect_filled(screen, 0.0, egui::Color32::from_black_alpha(160));
            painter.text(
                screen.center(),
                egui::Align2::CENTER_CENTER,
                "drop a scene file with its meshes and textures, or a reference EXR",
                egui::FontId::proportional(18.0),
                egui::Color32::WHITE,
            );
        }
        page::publish_controls(&self.controls);
        page::report(&self.status());
        ctx.request_repaint();
    }
}
