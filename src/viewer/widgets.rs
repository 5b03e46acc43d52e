//! The settings panel's widgets (egui): the A | B settings grid under the CLI's names, path rows, the
//! statistics grid and the false-colour legend, with the small helpers they share.

use crate::render::display::{self, View};
use crate::render::settings::*;
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Vec2};

/// Messages can quote compiler output (naga draws boxes with U+2500..): keep what egui's default
/// fonts can draw.
pub fn plain(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '\u{2500}'..='\u{257F}' => '-',
            c if (c as u32) < 0x2000
                || matches!(
                    c,
                    '\u{2013}' | '\u{2014}' | '\u{2026}' | '\u{2018}' | '\u{2019}' | '\u{201C}' | '\u{201D}'
                ) =>
            {
                c
            }
            _ => '?',
        })
        .collect()
}

/// A label and a widget named by it (kittest and screen readers find the widget by the label).
pub fn labelled(ui: &mut egui::Ui, name: &str, add: impl FnOnce(&mut egui::Ui) -> egui::Response, changed: &mut bool) {
    ui.horizontal(|ui| {
        let l = ui.label(name);
        let r = add(ui).labelled_by(l.id);
        *changed |= r.changed();
    });
}

/// A combo box named `label` choosing among `all`; returns whether the value changed.
pub fn choice<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    id: String,
    label: &str,
    v: &mut T,
    all: &[T],
    name: impl Fn(&T) -> &'static str,
) -> bool {
    let mut changed = false;
    egui::ComboBox::new(id, label).selected_text(name(v)).width(130.0).show_ui(ui, |ui| {
        for x in all {
            if ui.selectable_value(v, *x, name(x)).changed() {
                changed = true;
            }
        }
    });
    changed
}

/// A combo box without a label of its own, named by `label` (the row's label in a grid).
pub fn grid_choice<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    id: String,
    label: egui::Id,
    v: &mut T,
    all: &[T],
    name: impl Fn(&T) -> &'static str,
) -> bool {
    let mut changed = false;
    let r = egui::ComboBox::from_id_salt(id).selected_text(name(v)).width(112.0).show_ui(ui, |ui| {
        for x in all {
            if ui.selectable_value(v, *x, name(x)).changed() {
                changed = true;
            }
        }
    });
    r.response.labelled_by(label);
    changed
}

/// Every estimator setting of one or two sides, one row per setting named as on the command line,
/// one column per side; returns which sides changed.
pub fn settings_grid(ui: &mut egui::Ui, settings: &mut [Settings; 2], sides: usize) -> [bool; 2] {
    let mut c = [false; 2];
    egui::Grid::new("mislab-estimators").num_columns(1 + sides).spacing([6.0, 3.0]).show(ui, |ui| {
        if sides == 2 {
            ui.label("");
            ui.strong("A");
            ui.strong("B");
            ui.end_row();
        }
        macro_rules! combo_row {
            ($name:literal, $field:ident, $ty:ty) => {{
                let l = ui.label($name).id;
                for i in 0..sides {
                    c[i] |=
                        grid_choice(ui, format!("{i}-{}", $name), l, &mut settings[i].$field, <$ty>::ALL, |v| v.name());
                }
                ui.end_row();
            }};
        }
        macro_rules! drag_row {
            ($name:literal, $field:ident, $drag:expr) => {{
                let l = ui.label($name).id;
                for i in 0..sides {
                    let r = ui.add($drag(&mut settings[i].$field)).labelled_by(l);
                    c[i] |= r.changed();
                }
                ui.end_row();
            }};
        }
        combo_row!("mode", mode, Mode);
        combo_row!("strategy", strategy, Strategy);
        combo_row!("light-sampling", light_sampling, LightSampling);
        combo_row!("env-sampling", env_sampling, EnvSampling);
        combo_row!("light-select", light_select, LightSelect);
        combo_row!("heuristic", heuristic, Heuristic);
        drag_row!("power-beta", power_beta, |v| egui::DragValue::new(v).range(0.1..=16.0).speed(0.05));
        combo_row!("mis", mis, MisKind);
        drag_row!("light-samples", light_samples, |v| egui::DragValue::new(v).range(0..=64));
        drag_row!("ris-candidates", ris_candidates, |v| egui::DragValue::new(v).range(1..=64));
        drag_row!("bsdf-samples", bsdf_samples, |v| egui::DragValue::new(v).range(0..=64));
        drag_row!("first-hit-light-split", first_hit_light_split, |v| egui::DragValue::new(v).range(1..=64));
        combo_row!("sampler", sampler, SamplerKind);
        drag_row!("max-depth", max_depth, |v| egui::DragValue::new(v).range(1..=256));
        drag_row!("seed", seed, |v| egui::DragValue::new(v));
    });
    c
}

/// A path field with its button; true when the button is clicked or Enter pressed in the field.
pub fn path_row(ui: &mut egui::Ui, name: &str, value: &mut String, button: &str) -> bool {
    let mut go = false;
    ui.horizontal(|ui| {
        let l = ui.label(name);
        let r = ui.add(egui::TextEdit::singleline(value).desired_width(150.0)).labelled_by(l.id);
        if r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            go = true;
        }
        if ui.button(button).clicked() {
            go = true;
        }
    });
    go && !value.trim().is_empty()
}

pub fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_else(|| "—".into())
}

/// The statistics of one or two sides as a grid.
#[cfg(not(target_arch = "wasm32"))]
pub fn stats_grid(ui: &mut egui::Ui, stats: &[super::engine::SideStats], has_reference: bool) {
    egui::Grid::new("mislab-stats").num_columns(stats.len() + 1).striped(true).show(ui, |ui| {
        if stats.len() == 2 {
            ui.label("");
            ui.strong("A");
            ui.strong("B");
            ui.end_row();
        }
        let row = |ui: &mut egui::Ui, name: &str, f: &dyn Fn(&super::engine::SideStats) -> String| {
            ui.label(name);
            for s in stats {
                ui.monospace(f(s));
            }
            ui.end_row();
        };
        let height = |s: &super::engine::SideStats| s.settings.height.max(1);
        row(ui, "spp", &|s| {
            if s.pass_rows > 0 {
                format!("{} (+{}/{} rows)", s.spp, s.pass_rows, height(s))
            } else {
                s.spp.to_string()
            }
        });
        row(ui, "samples/s", &|s| format!("{:.2} M", s.samples_per_s / 1e6));
        row(ui, "GPU ms/frame", &|s| format!("{:.1}", s.gpu_ms));
        row(ui, "Mrays/s", &|s| format!("{:.2}", s.mrays_per_s));
        row(ui, "mean rel. std. error", &|s| fmt_opt(s.image.mean_rel_se, 4));
        if has_reference {
            row(ui, "RMSE vs reference", &|s| fmt_opt(s.image.rmse, 5));
            row(ui, "relMSE vs reference", &|s| fmt_opt(s.image.rel_mse, 5));
        }
        row(ui, "NaN/Inf samples", &|s| format!("{} ({} px)", s.nonfinite_samples, s.image.nonfinite_px));
        row(ui, "pipeline", &|s| match s.pipeline {
            super::engine::PipelineState::Specialised => "specialised".into(),
            super::engine::PipelineState::Generic => "generic".into(),
            super::engine::PipelineState::Compiling => "compiling".into(),
        });
    });
}

/// The false-colour legend: the colour bar with a tick per decade.
pub fn legend(ui: &mut egui::Ui, view: View, range: [f32; 2]) {
    let title = match view {
        View::StdErr => "standard error of the pixel mean (log scale)",
        _ => "relMSE = (x - ref)^2 / (ref^2 + 0.01) (log scale)",
    };
    ui.small(title);
    let (rect, _) = ui.allocate_exact_size(Vec2::new(ui.available_width().min(300.0), 16.0), Sense::hover());
    let painter = ui.painter_at(rect.expand(1.0));
    let n = 64;
    for k in 0..n {
        let t = (k as f32 + 0.5) / n as f32;
        let c = display::false_colour(t).map(|v| (v * 255.0 + 0.5) as u8);
        let x0 = rect.left() + rect.width() * k as f32 / n as f32;
        let x1 = rect.left() + rect.width() * (k + 1) as f32 / n as f32 + 0.5;
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x0, rect.top()), Pos2::new(x1, rect.bottom())),
            0.0,
            Color32::from_rgb(c[0], c[1], c[2]),
        );
    }
    let (tick_rect, _) = ui.allocate_exact_size(Vec2::new(rect.width(), 14.0), Sense::hover());
    let p2 = ui.painter_at(tick_rect.expand(8.0));
    let (lo, hi) = (range[0], range[1]);
    let first = lo.ceil() as i32;
    let last = hi.floor() as i32;
    let step = (((last - first) as f32 / 6.0).ceil() as i32).max(1);
    let mut d = first;
    while d <= last {
        let x = rect.left() + rect.width() * (d as f32 - lo) / (hi - lo);
        // Keep the end labels inside the bar's width.
        let align = if x < rect.left() + 12.0 {
            egui::Align2::LEFT_TOP
        } else if x > rect.right() - 12.0 {
            egui::Align2::RIGHT_TOP
        } else {
            egui::Align2::CENTER_TOP
        };
        p2.text(
            Pos2::new(x, tick_rect.top()),
            align,
            format!("1e{d}"),
            egui::FontId::monospace(10.0),
            ui.visuals().text_color(),
        );
        d += step;
    }
}
