//! Plots (plotters): PNG through an in-memory RGB bitmap encoded by `image`, and SVG. Text uses egui's Hack
//! font, registered with plotters' ab_glyph text backend (no system fonts needed).

use super::ticks;
use super::ConfigSummary;
use crate::lab::LabError;
use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Registers the font once.
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for family in ["sans-serif", "serif", "monospace"] {
            for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic, FontStyle::Oblique] {
                let _ = plotters::style::register_font(family, style, epaint_default_fonts::HACK_REGULAR);
            }
        }
    });
}

/// Something drawn on any backend.
pub trait Figure {
    /// Draws on `root`.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), LabError>;
}

/// Writes `figure` as `base.png` and `base.svg` in `dir`.
pub fn save(dir: &Path, base: &str, size: (u32, u32), figure: &impl Figure) -> Result<(), LabError> {
    save_png(&dir.join(format!("{base}.png")), size, figure)?;
    save_svg(&dir.join(format!("{base}.svg")), size, figure)
}

/// Writes `figure` as PNG.
pub fn save_png(path: &Path, (w, h): (u32, u32), figure: &impl Figure) -> Result<(), LabError> {
    register_font();
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        figure.draw(&root)?;
        root.present().map_err(|e| LabError::Plot(e.to_string()))?;
    }
    image::save_buffer(path, &buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| LabError::Input(format!("{}: {e}", path.display())))
}

/// Writes `figure` as SVG.
pub fn save_svg(path: &Path, size: (u32, u32), figure: &impl Figure) -> Result<(), LabError> {
    register_font();
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        figure.draw(&root)?;
        root.present().map_err(|e| LabError::Plot(e.to_string()))?;
    }
    std::fs::write(path, text).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))
}

/// Line colours (Okabe–Ito, distinguishable for colour-blind readers).
pub fn color(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(0, 114, 178),
        RGBColor(213, 94, 0),
        RGBColor(0, 158, 115),
        RGBColor(204, 121, 167),
        RGBColor(230, 159, 0),
        RGBColor(86, 180, 233),
        RGBColor(0, 0, 0),
        RGBColor(240, 228, 66),
    ];
    C[i % C.len()]
}

/// A viridis-like map of t ∈ [0, 1].
pub fn colormap(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

type LogAxis = WithKeyPoints<LogCoord<f64>>;

/// A log x axis with readable ticks: powers of two as integers for sample counts, else `ticks::log_ticks`.
fn x_axis(lo: f64, hi: f64, integer: bool) -> LogAxis {
    let (bold, light) = if integer { (ticks::spp_ticks(lo, hi), vec![]) } else { ticks::log_ticks(lo, hi) };
    (lo..hi).log_scale().with_key_points(bold).with_light_points(light)
}

fn y_axis(lo: f64, hi: f64) -> LogAxis {
    let (bold, light) = ticks::log_ticks(lo, hi);
    (lo..hi).log_scale().with_key_points(bold).with_light_points(light)
}

/// Log-log lines of mean relMSE with min–max bars over seeds, against seconds or spp.
pub struct ErrorPlot {
    /// Caption.
    pub title: String,
    /// x-axis description.
    pub x_desc: String,
    /// Whether x is a sample count (integer ticks at powers of two).
    pub integer_x: bool,
    /// Per configuration: label and points (x, mean, min, max).
    pub series: Vec<(String, Vec<(f64, f64, f64, f64)>)>,
}

impl Figure for ErrorPlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), LabError> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| LabError::Plot(e.to_string());
        root.fill(&WHITE).map_err(err)?;
        let pts = self.series.iter().flat_map(|s| s.1.iter()).filter(|p| p.0 > 0.0 && p.2 > 0.0 && p.3.is_finite());
        let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
        for p in pts {
            x0 = x0.min(p.0);
            x1 = x1.max(p.0);
            y0 = y0.min(p.2);
            y1 = y1.max(p.3);
        }
        if !(x0.is_finite() && y0.is_finite() && x1 > 0.0 && y1 > 0.0) {
            return Ok(());
        }
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(72)
            .build_cartesian_2d(x_axis(x0 / 1.3, x1 * 1.3, self.integer_x), y_axis(y0 / 1.5, y1 * 1.5))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(self.x_desc.as_str())
            .y_desc("relMSE")
            .x_label_formatter(&|v| ticks::label(*v))
            .y_label_formatter(&|v| ticks::label(*v))
            .draw()
            .map_err(err)?;
        for (i, (label, p)) in self.series.iter().enumerate() {
            let c = color(i);
            let p: Vec<_> = p.iter().copied().filter(|q| q.0 > 0.0 && q.1 > 0.0).collect();
            chart
                .draw_series(LineSeries::new(p.iter().map(|q| (q.0, q.1)), c.stroke_width(2)))
                .map_err(err)?
                .label(label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
            chart
                .draw_series(
                    p.iter().map(|q| ErrorBar::new_vertical(q.0, q.2.max(y0 / 1.5), q.1, q.3, c.stroke_width(1), 6)),
                )
                .map_err(err)?;
            chart.draw_series(p.iter().map(|q| Circle::new((q.0, q.1), 3, c.filled()))).map_err(err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        Ok(())
    }
}

/// relMSE against seconds and against spp, one line per configuration.
pub fn error_plots(dir: &Path, base: &str, title: &str, sums: &[ConfigSummary]) -> Result<(), LabError> {
    let series = |by_time: bool| -> Vec<(String, Vec<(f64, f64, f64, f64)>)> {
        sums.iter()
            .map(|s| {
                let pts = (0..s.spp.len())
                    .map(|i| {
                        (
                            if by_time { s.seconds[i] } else { s.spp[i] as f64 },
                            s.relmse[i][0],
                            s.relmse[i][1],
                            s.relmse[i][2],
                        )
                    })
                    .collect();
                (s.config.clone(), pts)
            })
            .collect()
    };
    save(
        dir,
        &format!("{base}-error-vs-time"),
        (900, 600),
        &ErrorPlot { title: title.into(), x_desc: "GPU seconds".into(), integer_x: false, series: series(true) },
    )?;
    save(
        dir,
        &format!("{base}-error-vs-spp"),
        (900, 600),
        &ErrorPlot { title: title.into(), x_desc: "samples per pixel".into(), integer_x: true, series: series(false) },
    )
}

/// A grid of scalar images on one colour scale.
pub struct Heatmaps {
    /// Caption.
    pub title: String,
    /// Per panel: label, and a row-major image of `cells.0 × cells.1` values.
    pub panels: Vec<(String, Vec<f64>)>,
    /// Image size of every panel.
    pub cells: (usize, usize),
    /// Value range mapped to the colour map (log10 when `log`).
    pub range: (f64, f64),
    /// Whether the scale is log10.
    pub log: bool,
    /// Colour-bar caption.
    pub legend: String,
}

impl Figure for Heatmaps {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), LabError> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| LabError::Plot(e.to_string());
        root.fill(&WHITE).map_err(err)?;
        let (w, h) = root.dim_in_pixel();
        let titled = root.titled(&self.title, ("sans-serif", 18)).map_err(err)?;
        let (body, bar) = titled.split_vertically(h.saturating_sub(80).max(10));
        let n = self.panels.len().max(1);
        let areas = body.split_evenly((1, n));
        let map = |v: f64| -> RGBColor {
            let x = if self.log { v.max(1e-30).log10() } else { v };
            colormap((x - self.range.0) / (self.range.1 - self.range.0).max(1e-30))
        };
        for (area, (label, img)) in areas.iter().zip(&self.panels) {
            let (aw, ah) = area.dim_in_pixel();
            let side = (aw.min(ah.saturating_sub(24)) as f64).max(1.0);
            let cw = side / self.cells.0.max(self.cells.1) as f64;
            let x0 = (aw as f64 - cw * self.cells.0 as f64) / 2.0;
            area.draw(&Text::new(label.clone(), (x0 as i32, 2), ("sans-serif", 14))).map_err(err)?;
            for y in 0..self.cells.1 {
                for x in 0..self.cells.0 {
                    let c = map(img[y * self.cells.0 + x]);
                    let (px, py) = (x0 + x as f64 * cw, 22.0 + y as f64 * cw);
                    area.draw(&Rectangle::new(
                        [(px as i32, py as i32), ((px + cw).ceil() as i32, (py + cw).ceil() as i32)],
                        c.filled(),
                    ))
                    .map_err(err)?;
                }
            }
        }
        // Colour bar.
        let steps = 64;
        let bw = (w as f64 * 0.6) / steps as f64;
        let bx = w as f64 * 0.2;
        for i in 0..steps {
            let t = i as f64 / (steps - 1) as f64;
            bar.draw(&Rectangle::new(
                [((bx + i as f64 * bw) as i32, 10), ((bx + (i + 1) as f64 * bw).ceil() as i32, 30)],
                colormap(t).filled(),
            ))
            .map_err(err)?;
        }
        // Ends as values (not "1e0.6"), and each whole decade between them marked under the bar.
        let fmt = |v: f64| if self.log { ticks::label_log10(v) } else { format!("{v:.3}") };
        bar.draw(&Text::new(fmt(self.range.0), (bx as i32 - 60, 14), ("sans-serif", 13))).map_err(err)?;
        bar.draw(&Text::new(fmt(self.range.1), ((bx + steps as f64 * bw) as i32 + 8, 14), ("sans-serif", 13)))
            .map_err(err)?;
        let span = (self.range.1 - self.range.0).max(1e-30);
        if self.log {
            for d in (self.range.0.ceil() as i32)..=(self.range.1.floor() as i32) {
                let x = (bx + (d as f64 - self.range.0) / span * steps as f64 * bw) as i32;
                bar.draw(&PathElement::new(vec![(x, 30), (x, 35)], BLACK)).map_err(err)?;
                bar.draw(&Text::new(ticks::label(10f64.powi(d)), (x - 12, 34), ("sans-serif", 12))).map_err(err)?;
            }
        }
        bar.draw(&Text::new(self.legend.clone(), (bx as i32, 50), ("sans-serif", 13))).map_err(err)?;
        Ok(())
    }
}

/// Box-filters a `w`×`h` image down to at most `max` cells per side.
pub fn downsample(img: &[f64], w: usize, h: usize, max: usize) -> (Vec<f64>, usize, usize) {
    let f = w.max(h).div_ceil(max).max(1);
    let (cw, ch) = (w.div_ceil(f), h.div_ceil(f));
    let mut out = vec![0.0; cw * ch];
    let mut n = vec![0u32; cw * ch];
    for y in 0..h {
        for x in 0..w {
            let k = (y / f) * cw + x / f;
            out[k] += img[y * w + x];
            n[k] += 1;
        }
    }
    out.iter_mut().zip(&n).for_each(|(v, &c)| *v /= c.max(1) as f64);
    (out, cw, ch)
}

/// Per-pixel relMSE heatmaps (log scale, shared range), PNG at up to 128 cells per side, SVG at up to 48.
pub fn heatmaps(
    dir: &Path,
    base: &str,
    title: &str,
    w: u32,
    h: u32,
    maps: &[(String, Vec<f64>)],
) -> Result<(), LabError> {
    if maps.is_empty() {
        return Ok(());
    }
    let name = format!("{base}-heatmaps");
    for (max, svg) in [(128usize, false), (48, true)] {
        let mut panels = vec![];
        let mut cells = (0, 0);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for (label, m) in maps {
            let (d, cw, ch) = downsample(m, w as usize, h as usize, max);
            cells = (cw, ch);
            for &v in &d {
                if v > 0.0 && v.is_finite() {
                    lo = lo.min(v.log10());
                    hi = hi.max(v.log10());
                }
            }
            panels.push((label.clone(), d));
        }
        // Clip the colour range to 4 decades below the maximum so a few exact pixels do not flatten the rest.
        let lo = lo.max(hi - 4.0);
        let fig = Heatmaps {
            title: format!("{title}: per-pixel relMSE at the last point, mean over seeds"),
            panels,
            cells,
            range: (lo, hi.max(lo + 1e-6)),
            log: true,
            legend: "per-pixel relMSE (log scale)".into(),
        };
        let size = (260 * maps.len() as u32 + 40, 400);
        if svg {
            save_svg(&dir.join(format!("{name}.svg")), size, &fig)?;
        } else {
            save_png(&dir.join(format!("{name}.png")), size, &fig)?;
        }
    }
    Ok(())
}
