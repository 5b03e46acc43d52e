//! The viewer's window contents (egui): the settings panel (every estimator setting under its CLI
//! name), display options with the false-colour legend, the A | B comparison with its divider, the
//! statistics, camera control, opening and saving files. Runs the same under eframe and egui_kittest.

use super::camera::Orbit;
use super::engine::{Command, DisplayOptions, EngineHandle, Frame, Side, SideStats};
use super::widgets::{choice, labelled, legend, path_row, plain, settings_grid, stats_grid};
use crate::render::display::{self, View, TONEMAPS};
use crate::render::settings::*;
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Vec2};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Width of the settings panel, points.
pub const PANEL_WIDTH: f32 = 330.0;

/// A settings change whose first image the UI is waiting for (to measure the toggle latency).
struct PendingToggle {
    side: usize,
    generation_before: u64,
    sent: Instant,
}

/// The viewer's UI state. `ui` draws one frame.
pub struct Viewer {
    engine: EngineHandle,
    /// Settings of side A and B as the panel shows them.
    pub settings: [Settings; 2],
    /// Whether the comparison is on.
    pub compare: bool,
    /// Display options.
    pub display: DisplayOptions,
    orbit: Option<Orbit>,
    texture: Option<egui::TextureHandle>,
    frame: Option<Arc<Frame>>,
    /// Paths typed (or dropped) into the panel's fields.
    pub scene_path: String,
    /// Environment map path.
    pub env_path: String,
    /// Reference EXR path.
    pub reference_path: String,
    /// Where "save" writes.
    pub save_path: String,
    status: String,
    dragging_divider: bool,
    ui_frames: VecDeque<Instant>,
    pending: Option<PendingToggle>,
    /// Milliseconds from each estimator toggle to the UI receiving the first image of the new estimator.
    pub toggle_latencies_ms: Vec<f64>,
    /// Wall-clock intervals between UI frames, seconds (the last few hundred).
    pub frame_intervals: VecDeque<f64>,
    last_ui_frame: Option<Instant>,
    taken_serial: u64,
}

impl Viewer {
    /// A viewer driving `engine`, whose starting state is `settings` / `compare` / `display`.
    pub fn new(
        engine: EngineHandle,
        settings: [Settings; 2],
        compare: bool,
        display: DisplayOptions,
        scene_path: String,
    ) -> Viewer {
        Viewer {
            engine,
            settings,
            compare,
            display,
            orbit: None,
            texture: None,
            frame: None,
            scene_path,
            env_path: String::new(),
            reference_path: String::new(),
            save_path: "view.png".into(),
            status: String::new(),
            dragging_divider: false,
            ui_frames: VecDeque::new(),
            pending: None,
            toggle_latencies_ms: Vec::new(),
            frame_intervals: VecDeque::new(),
            last_ui_frame: None,
            taken_serial: 0,
        }
    }

    /// The engine (tests read its shared state).
    pub fn engine(&self) -> &EngineHandle {
        &self.engine
    }

    /// The frame shown now.
    pub fn frame(&self) -> Option<&Arc<Frame>> {
        self.frame.as_ref()
    }

    /// UI frames per second over the last two seconds.
    pub fn ui_fps(&self) -> f64 {
        match (self.ui_frames.front(), self.ui_frames.back()) {
            (Some(a), Some(b)) if self.ui_frames.len() > 1 => {
                (self.ui_frames.len() - 1) as f64 / (*b - *a).as_secs_f64().max(1e-9)
            }
            _ => 0.0,
        }
    }

    /// Sends side `i`'s settings (after a change in the panel) and starts timing the toggle.
    pub fn apply_settings(&mut self, i: usize) {
        if let Err(e) = self.settings[i].validate() {
            self.status = e.to_string();
            return;
        }
        let generation_before = self.engine.shared().stats[i].generation;
        self.pending = Some(PendingToggle { side: i, generation_before, sent: Instant::now() });
        let side = if i == 0 { Side::A } else { Side::B };
        self.engine.send(Command::Settings(side, self.settings[i].clone()));
    }

    fn take_frame(&mut self, ctx: &egui::Context) {
        let (frame, stats) = {
            let s = self.engine.shared();
            (s.frame.clone(), [s.stats[0].generation, s.stats[1].generation])
        };
        let _ = stats;
        let Some(frame) = frame else { return };
        if self.frame.as_ref().is_some_and(|f| f.serial == frame.serial) {
            return;
        }
        let image =
            egui::ColorImage::from_rgba_premultiplied([frame.width as usize, frame.height as usize], &frame.rgba);
        match &mut self.texture {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.texture = Some(ctx.load_texture("mislab-film", image, egui::TextureOptions::NEAREST)),
        }
        if let Some(p) = &self.pending {
            if frame.generations[p.side] > p.generation_before && frame.shown[p.side] {
                self.toggle_latencies_ms.push(p.sent.elapsed().as_secs_f64() * 1e3);
                self.pending = None;
            }
        }
        self.engine.shared().ui_taken = frame.serial;
        self.taken_serial = frame.serial;
        // One more UI frame soon: its start tells the engine this one has been painted.
        ctx.request_repaint();
        self.frame = Some(frame);
    }

    /// Tells the engine how long the UI's frames take (eframe measures building + painting).
    pub fn set_ui_cost(&self, seconds: f64) {
        self.engine.shared().ui_cost_s = seconds;
    }

    fn send_display(&self) {
        self.engine.send(Command::Display(self.display));
    }

    /// Draws one frame of the whole window.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        if let Some(t) = self.last_ui_frame {
            self.frame_intervals.push_back((now - t).as_secs_f64());
            if self.frame_intervals.len() > 600 {
                self.frame_intervals.pop_front();
            }
        }
        self.last_ui_frame = Some(now);
        self.ui_frames.push_back(now);
        while self.ui_frames.front().is_some_and(|t| (now - *t).as_secs_f64() > 2.0) {
            self.ui_frames.pop_front();
        }
        let ctx = ui.ctx().clone();
        if self.taken_serial > 0 {
            // Everything taken in earlier UI frames has been painted by now.
            self.engine.shared().ui_painted = self.taken_serial;
        }
        self.take_frame(&ctx);
        self.dropped_files(&ctx);
        egui::Panel::left("mislab-panel").default_size(PANEL_WIDTH).resizable(false).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.image_area(ui));
        let fatal = self.engine.shared().fatal.clone();
        if let Some(f) = fatal {
            egui::Window::new("The renderer stopped").collapsible(false).resizable(false).show(&ctx, |ui| {
                ui.label(plain(&f));
                ui.label("Close the window to exit.");
            });
        }
    }

    fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).filter(|p| !p.as_os_str().is_empty()).collect()
        });
        for p in dropped {
            self.open_path(p);
        }
    }

    /// Opens a dropped (or typed) file by its kind: a scene (.gltf/.glb/.toml), an environment map
    /// (.hdr, or .exr of another size than the film), or a reference (.exr of the film's size).
    pub fn open_path(&mut self, p: PathBuf) {
        let ext = p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
        let s = p.display().to_string();
        match ext.as_str() {
            "gltf" | "glb" | "toml" => {
                self.scene_path = s.clone();
                self.engine.send(Command::OpenScene(s));
                self.orbit = None;
            }
            "hdr" => {
                self.env_path = s;
                self.engine.send(Command::OpenEnv(p));
            }
            "exr" => {
                let film = (self.settings[0].width, self.settings[0].height);
                let dims = image::ImageReader::open(&p)
                    .ok()
                    .and_then(|r| r.with_guessed_format().ok())
                    .and_then(|r| r.into_dimensions().ok());
                if dims == Some(film) {
                    self.reference_path = s;
                    self.engine.send(Command::LoadReference(p));
                } else {
                    self.env_path = s;
                    self.engine.send(Command::OpenEnv(p));
                }
            }
            _ => {
                self.status =
                    format!("{s}: not a scene (.gltf/.glb/.toml), environment (.hdr/.exr) or reference (.exr)")
            }
        }
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("mislab view");
        let (scene, device, message, compiling, fps_line) = {
            let s = self.engine.shared();
            (s.scene.clone(), s.device.clone(), s.message.clone(), s.compiling, format!("{} render frames", s.frames))
        };
        ui.label(format!("scene: {scene}"));
        ui.small(format!("device: {device}"));
        ui.small(format!(
            "UI {:.0} frames/s · {fps_line}{}",
            self.ui_fps(),
            if compiling > 0 { format!(" · compiling {compiling} pipeline(s)") } else { String::new() }
        ));
        if let Some(ms) = self.toggle_latencies_ms.last() {
            ui.small(format!("last toggle to first image: {ms:.0} ms"));
        }
        if let Some(m) = message {
            ui.small(plain(&m));
        }
        if !self.status.is_empty() {
            ui.colored_label(Color32::from_rgb(230, 120, 60), self.status.clone());
        }
        ui.separator();

        let sides = if self.compare { 2 } else { 1 };
        ui.strong(if self.compare { "Estimators A | B" } else { "Estimator" });
        let changed = settings_grid(ui, &mut self.settings, sides);
        for (i, c) in changed.into_iter().enumerate() {
            if c {
                self.apply_settings(i);
            }
        }
        ui.separator();

        ui.strong("Display");
        let mut dirty = false;
        labelled(
            ui,
            "exposure",
            |ui| ui.add(egui::Slider::new(&mut self.display.exposure, -10.0..=10.0).step_by(0.1).suffix(" stops")),
            &mut dirty,
        );
        dirty |=
            choice(ui, "tonemap".into(), "tonemap", &mut self.display.tonemap, TONEMAPS, |t| display::tonemap_name(*t));
        dirty |= choice(ui, "view".into(), "view", &mut self.display.view, View::ALL, |v| v.name());
        if self.display.view.false_colour() {
            labelled(
                ui,
                "scale min (log10)",
                |ui| ui.add(egui::DragValue::new(&mut self.display.log_range[0]).range(-12.0..=12.0).speed(0.05)),
                &mut dirty,
            );
            labelled(
                ui,
                "scale max (log10)",
                |ui| ui.add(egui::DragValue::new(&mut self.display.log_range[1]).range(-12.0..=12.0).speed(0.05)),
                &mut dirty,
            );
            if self.display.log_range[1] <= self.display.log_range[0] + 0.1 {
                self.display.log_range[1] = self.display.log_range[0] + 0.1;
            }
            legend(ui, self.display.view, self.display.log_range);
        }
        if dirty {
            self.send_display();
            for s in &mut self.settings {
                s.exposure = self.display.exposure;
            }
        }
        ui.separator();

        ui.horizontal(|ui| {
            let mut compare = self.compare;
            if ui.checkbox(&mut compare, "compare A | B").changed() {
                self.compare = compare;
                if compare {
                    self.apply_settings(1);
                }
                self.engine.send(Command::Compare(compare));
            }
            if self.compare && ui.button("copy A to B").clicked() {
                self.settings[1] = self.settings[0].clone();
                self.apply_settings(1);
            }
        });
        ui.separator();

        let stats = self.engine.shared().stats.clone();
        stats_grid(ui, &stats[..sides], self.engine.shared().has_reference);
        ui.separator();

        ui.horizontal(|ui| {
            if ui.button("reset camera").clicked() {
                let home = self.engine.shared().home_camera.clone();
                self.orbit = None;
                self.engine.send(Command::Camera(home));
            }
            ui.small("drag: orbit · right drag: pan · wheel: zoom");
        });
        ui.separator();
        egui::CollapsingHeader::new("Files").default_open(false).show(ui, |ui| self.files_ui(ui));
    }

    fn files_ui(&mut self, ui: &mut egui::Ui) {
        ui.small("or drop a .gltf/.glb/.toml scene, an .hdr/.exr environment or a reference .exr on the window");
        if path_row(ui, "scene path", &mut self.scene_path, "open scene") {
            let p = self.scene_path.clone();
            self.orbit = None;
            self.engine.send(Command::OpenScene(p));
        }
        if path_row(ui, "environment path", &mut self.env_path, "load environment") {
            self.engine.send(Command::OpenEnv(PathBuf::from(&self.env_path)));
        }
        if path_row(ui, "reference path", &mut self.reference_path, "load reference") {
            self.engine.send(Command::LoadReference(PathBuf::from(&self.reference_path)));
        }
        if path_row(ui, "save path", &mut self.save_path, "save") {
            self.save(PathBuf::from(&self.save_path));
        }
    }

    /// Saves what is shown: .png = the displayed image (the active view, both sides); .exr = the linear
    /// film of side A (and B as `<stem>-b.exr`).
    pub fn save(&mut self, path: PathBuf) {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "png" => match &self.frame {
                Some(f) => {
                    let img = image::RgbaImage::from_raw(f.width, f.height, f.rgba.clone())
                        .expect("frame size matches its pixels");
                    self.status = match img.save(&path) {
                        Ok(()) => format!("wrote {}", path.display()),
                        Err(e) => format!("{}: {e}", path.display()),
                    };
                }
                None => self.status = "nothing rendered yet".into(),
            },
            "exr" => {
                self.status.clear();
                self.engine.send(Command::SaveExr(path));
            }
            _ => self.status = format!("{}: save as .png (what is shown) or .exr (linear radiance)", path.display()),
        }
    }

    fn image_area(&mut self, ui: &mut egui::Ui) {
        let (w, h) = (self.settings[0].width as f32, self.settings[0].height as f32);
        let avail = ui.available_size();
        let scale = (avail.x / w).min((avail.y - 4.0) / h).max(0.05);
        let size = Vec2::new(w, h) * scale;
        let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let painter = ui.painter_at(rect);
        match &self.texture {
            Some(t) => {
                painter.image(t.id(), rect, Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)), Color32::WHITE);
            }
            None => {
                painter.rect_filled(rect, 0.0, Color32::from_gray(20));
                painter.text(
                    rect.center(),
                    egui::Align2::CENTER_CENTER,
                    "compiling the render pipeline...",
                    egui::FontId::proportional(16.0),
                    Color32::GRAY,
                );
            }
        }
        let stats = self.engine.shared().stats.clone();
        // The divider and the per-side labels.
        let font = egui::FontId::monospace(12.0);
        let label = |painter: &egui::Painter, pos: Pos2, align: egui::Align2, text: String| {
            let galley = painter.layout_no_wrap(text, font.clone(), Color32::WHITE);
            let r = align.anchor_size(pos, galley.size()).expand(3.0);
            painter.rect_filled(r, 3.0, Color32::from_black_alpha(170));
            painter.galley(r.min + Vec2::splat(3.0), galley, Color32::WHITE);
        };
        let side_text = |s: &SideStats, name: &str| format!("{name}{} · {} spp", s.settings.strategy, s.spp);
        if self.compare {
            let x = rect.left() + self.display.split.clamp(0.0, 1.0) * rect.width();
            painter.line_segment(
                [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
                egui::Stroke::new(2.0, Color32::WHITE),
            );
            painter.circle_filled(Pos2::new(x, rect.center().y), 6.0, Color32::WHITE);
            label(&painter, rect.left_top() + Vec2::splat(6.0), egui::Align2::LEFT_TOP, side_text(&stats[0], "A: "));
            label(
                &painter,
                rect.right_top() + Vec2::new(-6.0, 6.0),
                egui::Align2::RIGHT_TOP,
                side_text(&stats[1], "B: "),
            );
            let near_divider = |p: Option<Pos2>| p.is_some_and(|p| (p.x - x).abs() < 10.0);
            if response.drag_started() && near_divider(response.interact_pointer_pos()) {
                self.dragging_divider = true;
            }
            if self.dragging_divider {
                if let Some(p) = response.interact_pointer_pos() {
                    self.display.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
                    self.send_display();
                }
                if !response.dragged() {
                    self.dragging_divider = false;
                }
                return;
            }
            if response.hovered() && near_divider(response.hover_pos()) {
                ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
            }
        } else {
            label(&painter, rect.left_top() + Vec2::splat(6.0), egui::Align2::LEFT_TOP, side_text(&stats[0], ""));
        }
        // Camera: orbit, pan, zoom.
        let mut moved = false;
        let orbit = self.orbit.get_or_insert_with(|| {
            let s = self.engine.shared();
            Orbit::new(s.camera.clone(), s.pivot)
        });
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            if d != Vec2::ZERO {
                orbit.orbit(d.x * 0.01, d.y * 0.01);
                moved = true;
            }
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            let d = response.drag_delta();
            if d != Vec2::ZERO {
                orbit.pan(d.x, d.y, rect.height());
                moved = true;
            }
        }
        if response.hovered() {
            let scroll = ui.ctx().input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                orbit.zoom((-scroll * 0.002).exp());
                moved = true;
            }
        }
        if moved {
            let c = orbit.camera.clone();
            self.engine.send(Command::Camera(c));
        }
    }
}
