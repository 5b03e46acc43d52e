//! The page's panel (the scene, the strategies one click each, every estimator setting, the view, downloads,
//! statistics) and its image area (the A | B split follows a drag).

use super::{Source, WebLab, BUILTINS, STRATEGIES};
use eframe::egui;
use mislab::render::display::{self, View, TONEMAPS};
use mislab::viewer::widgets::{choice, fmt_opt, legend, settings_grid};

impl WebLab {
    /// A control a test may click, by name.
    fn mark(&mut self, name: impl Into<String>, r: &egui::Response) {
        self.controls.push((name.into(), r.rect));
    }

    pub(super) fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("mislab");
        ui.label("Monte Carlo estimators, live, on WebGPU");
        ui.separator();
        // The scene: a built-in one, or dropped / opened files.
        let mut pick: Option<usize> = None;
        let selected = match &self.source {
            Source::Builtin(i) => BUILTINS[*i].to_string(),
            Source::Files { .. } => self.scene_name.clone(),
        };
        egui::ComboBox::from_label("scene").selected_text(selected).show_ui(ui, |ui| {
            for (i, name) in BUILTINS.iter().enumerate() {
                if ui.selectable_label(matches!(self.source, Source::Builtin(j) if j == i), *name).clicked() {
                    pick = Some(i);
                }
            }
        });
        if let Some(i) = pick {
            self.source = Source::Builtin(i);
            self.load_scene();
        }
        let mut main_pick = None;
        if let Source::Files { set, main } = &self.source {
            if set.scenes.len() > 1 {
                let mut m = *main;
                egui::ComboBox::from_label("scene file").selected_text(set.scenes[m].as_str()).show_ui(ui, |ui| {
                    for (i, name) in set.scenes.iter().enumerate() {
                        ui.selectable_value(&mut m, i, name.as_str());
                    }
                });
                if m != *main {
                    main_pick = Some(m);
                }
            }
        }
        if let (Some(m), Source::Files { main, .. }) = (main_pick, &mut self.source) {
            *main = m;
            self.load_scene();
        }
        let open =
            ui.button("Open files…").on_hover_text("a scene file with its meshes and textures; or drop them here");
        self.mark("open-files", &open);
        if open.clicked() {
            self.inbox.choose_files();
        }
        if self.inbox.reading() {
            ui.label("reading files…");
        }
        ui.separator();

        // The lecture's strategies, one click each; side B's when comparing.
        for side in 0..1 + self.compare as usize {
            ui.label(if side == 0 { "strategy (A)" } else { "strategy (B)" });
            let mut s = self.settings[side].strategy;
            ui.horizontal_wrapped(|ui| {
                for strategy in STRATEGIES {
                    let r = ui.radio_value(&mut s, *strategy, strategy.name());
                    let tag = if side == 0 { "strategy" } else { "strategy-b" };
                    self.controls.push((format!("{tag}:{}", strategy.name()), r.rect));
                }
            });
            if s != self.settings[side].strategy {
                self.settings[side].strategy = s;
                self.set_settings(side);
            }
        }
        let mut compare = self.compare;
        let r = ui.checkbox(&mut compare, "compare A | B");
        self.mark("compare", &r);
        if compare != self.compare {
            self.compare = compare;
            self.build_sides();
        }
        ui.add(egui::Slider::new(&mut self.target_spp, 1..=4096).logarithmic(true).text("spp"));
        egui::CollapsingHeader::new("every estimator setting").default_open(false).show(ui, |ui| {
            let changed = settings_grid(ui, &mut self.settings, 1 + self.compare as usize);
            for (i, c) in changed.into_iter().enumerate() {
                if c {
                    self.set_settings(i);
                }
            }
        });
        ui.separator();

        // What is shown.
        ui.label("view");
        let mut view = self.view;
        ui.horizontal_wrapped(|ui| {
            for v in View::ALL {
                let enabled = *v != View::RelMse || self.reference.is_some();
                let r = ui.add_enabled(enabled, egui::RadioButton::new(view == *v, v.name()));
                if r.clicked() {
                    view = *v;
                }
                self.controls.push((format!("view:{}", v.name()), r.rect));
            }
        });
        if self.reference.is_none() {
            ui.small("relmse: drop a reference EXR of the film's size");
        }
        let mut dirty = view != self.view;
        self.view = view;
        dirty |= choice(ui, "tonemap".into(), "tonemap", &mut self.tonemap, TONEMAPS, |t| display::tonemap_name(*t));
        dirty |= ui.add(egui::Slider::new(&mut self.exposure, -8.0..=8.0).text("exposure")).changed();
        if self.view.false_colour() {
            dirty |= ui.add(egui::Slider::new(&mut self.log_range[0], -10.0..=0.0).text("log10 min")).changed();
            dirty |= ui.add(egui::Slider::new(&mut self.log_range[1], -6.0..=4.0).text("log10 max")).changed();
            legend(ui, self.view, self.log_range);
        }
        self.display_dirty |= dirty;
        ui.horizontal(|ui| {
            let png = ui.button("Save PNG");
            let exr = ui.button("Save EXR");
            self.mark("save-png", &png);
            self.mark("save-exr", &exr);
            if png.clicked() {
                self.save("png");
            }
            if exr.clicked() {
                self.save("exr");
            }
        });
        ui.separator();
        self.statistics(ui);
        let info = &self.ctx.info;
        ui.small(format!("{} ({:?})", info.name, info.backend));
        if let Some(r) = self.sides.first() {
            ui.small(if r.features().packed_scene { "scene tables: packed" } else { "scene tables: separate" });
        }
        for note in &self.notes {
            ui.small(note.as_str());
        }
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::RED, e.as_str());
        }
    }

    fn statistics(&self, ui: &mut egui::Ui) {
        let n = self.sides.len().max(1);
        egui::Grid::new("mislab-stats").num_columns(n + 1).striped(true).show(ui, |ui| {
            if n == 2 {
                ui.label("");
                ui.strong("A");
                ui.strong("B");
                ui.end_row();
            }
            let mut row = |name: &str, f: &dyn Fn(usize) -> String| {
                ui.label(name);
                for i in 0..n {
                    ui.monospace(f(i));
                }
                ui.end_row();
            };
            row("spp", &|i| self.shown.spp[i].to_string());
            row("mean", &|i| format!("{:.4}", self.shown.mean[i]));
            row("mean rel. std. error", &|i| fmt_opt(self.shown.stats[i].mean_rel_se, 4));
            if self.reference.is_some() {
                row("RMSE vs reference", &|i| fmt_opt(self.shown.stats[i].rmse, 5));
                row("relMSE vs reference", &|i| fmt_opt(self.shown.stats[i].rel_mse, 5));
            }
            row("NaN/Inf pixels", &|i| self.shown.stats[i].nonfinite_px.to_string());
        });
        ui.label(format!("{:.2} M samples/s (page)", self.rate.per_s / 1e6));
    }

    /// The image, fitted to the space; with a comparison, the split follows a drag across it.
    pub(super) fn image_area(&mut self, ui: &mut egui::Ui) {
        let Some(t) = &self.image else {
            ui.label(if self.error.is_some() { "" } else { "compiling the renderer…" });
            return;
        };
        let film = egui::vec2(self.width as f32, self.height as f32);
        let scale = (ui.available_width() / film.x).min(ui.available_height() / film.y).clamp(0.25, 4.0);
        let (rect, response) = ui.allocate_exact_size(film * scale, egui::Sense::click_and_drag());
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        ui.painter().image(t.id(), rect, uv, egui::Color32::WHITE);
        self.controls.push(("image".into(), rect));
        if self.sides.len() == 2 {
            if let Some(p) = response.interact_pointer_pos() {
                self.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
                self.display_dirty = true;
            }
            let x = rect.left() + self.split.clamp(0.0, 1.0) * rect.width();
            let stroke = egui::Stroke::new(1.5, egui::Color32::WHITE);
            ui.painter().line_segment([egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())], stroke);
            let label = |x: f32, align: egui::Align2, text: &str| {
                ui.painter().text(
                    egui::pos2(x, rect.top() + 4.0),
                    align,
                    text,
                    egui::FontId::proportional(14.0),
                    egui::Color32::WHITE,
                );
            };
            label(rect.left() + 6.0, egui::Align2::LEFT_TOP, &format!("A: {}", self.settings[0].strategy.name()));
            label(rect.right() - 6.0, egui::Align2::RIGHT_TOP, &format!("B: {}", self.settings[1].strategy.name()));
        }
    }
}
