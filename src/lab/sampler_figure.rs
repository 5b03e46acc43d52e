//! `mislab figure samplers`: for every sampler, the first 256 points of one pixel in the pixel-jitter pair and
//! in the first light-sample pair (coloured by index, so the progressive prefixes show), and the power spectrum
//! of the per-pixel error of a disc integrand over a 64×64 image at 1 and 4 spp (mean over seeds, DC at the
//! centre, relative to white noise) — the lecture's Halton/Hammersley and blue-noise slides. Computed with the
//! CPU twins of the WGSL samplers (src/render/samplers.rs), which tests/samplers.rs checks against the device.

use crate::lab::bench::plot::{self, Figure};
use crate::lab::LabError;
use crate::render::samplers::{self, SamplerParams, DIMS_CAMERA};
use crate::render::settings::SamplerKind;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Points shown per panel.
pub const POINTS: u32 = 256;
/// Side of the error image whose spectrum is shown: one tile of the blue-noise mask (a larger image repeats the
/// tile, which concentrates power on a lattice of frequencies).
pub const SPECTRUM_SIZE: usize = 64;
/// Seeds averaged in each spectrum.
pub const SPECTRUM_SEEDS: u32 = 8;
/// Sample counts of the spectrum rows.
pub const SPECTRUM_SPP: [u32; 2] = [1, 4];

/// In-place radix-2 FFT of (re, im) of power-of-two length.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(n.is_power_of_two() && im.len() == n);
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let a = -2.0 * std::f64::consts::PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (a * k as f64).sin_cos();
                let (u, v) = (start + k, start + k + len / 2);
                let (tr, ti) = (re[v] * c - im[v] * s, re[v] * s + im[v] * c);
                re[v] = re[u] - tr;
                im[v] = im[u] - ti;
                re[u] += tr;
                im[u] += ti;
            }
        }
        len <<= 1;
    }
}

/// |DFT|² of a square real image (side a power of two), DC moved to the centre.
pub fn power_spectrum(img: &[f64], side: usize) -> Vec<f64> {
    let mut re = img.to_vec();
    let mut im = vec![0.0; img.len()];
    for y in 0..side {
        fft(&mut re[y * side..(y + 1) * side], &mut im[y * side..(y + 1) * side]);
    }
    let (mut cr, mut ci) = (vec![0.0; side], vec![0.0; side]);
    for x in 0..side {
        for y in 0..side {
            cr[y] = re[y * side + x];
            ci[y] = im[y * side + x];
        }
        fft(&mut cr, &mut ci);
        for y in 0..side {
            re[y * side + x] = cr[y];
            im[y * side + x] = ci[y];
        }
    }
    let h = side / 2;
    let mut out = vec![0.0; img.len()];
    for y in 0..side {
        for x in 0..side {
            let k = y * side + x;
            out[((y + h) % side) * side + (x + h) % side] = (re[k] * re[k] + im[k] * im[k]) / img.len() as f64;
        }
    }
    out
}

/// The disc integrand of the spectrum rows: 1 inside radius 0.4 about the pixel's centre.
fn disc(u: [f32; 2]) -> f64 {
    let (x, y) = (u[0] as f64 - 0.5, u[1] as f64 - 0.5);
    if x * x + y * y < 0.16 {
        1.0
    } else {
        0.0
    }
}

/// Mean power spectrum of the per-pixel error of the disc integrand at `spp`, over `SPECTRUM_SEEDS` seeds, and
/// the error image of seed 0.
pub fn error_spectrum(kind: SamplerKind, spp: u32) -> (Vec<f64>, Vec<f64>) {
    error_spectrum_seeded(kind, spp, 0)
}

/// `error_spectrum` with the seeds shifted by `seed` × `SPECTRUM_SEEDS` (seed 0: the published figure's).
pub fn error_spectrum_seeded(kind: SamplerKind, spp: u32, seed: u32) -> (Vec<f64>, Vec<f64>) {
    let side = SPECTRUM_SIZE;
    let exact = std::f64::consts::PI * 0.16;
    let mut sum = vec![0.0; side * side];
    let mut first = vec![];
    let base = seed;
    for seed in 0..SPECTRUM_SEEDS {
        let p = SamplerParams {
            kind,
            seed: 1000u32.wrapping_add(base.wrapping_mul(SPECTRUM_SEEDS)).wrapping_add(seed),
            sampler_spp: spp,
            width: side as u32,
        };
        let err: Vec<f64> = (0..(side * side) as u32)
            .map(|px| (0..spp).map(|i| disc(samplers::sample_2d(&p, px, i, 0))).sum::<f64>() / spp as f64 - exact)
            .collect();
        let ps = power_spectrum(&err, side);
        sum.iter_mut().zip(&ps).for_each(|(a, b)| *a += b);
        if seed == 0 {
            first = err;
        }
    }
    sum.iter_mut().for_each(|v| *v /= SPECTRUM_SEEDS as f64);
    (sum, first)
}

/// Power within radius `side`/8 of DC (DC excluded) relative to the mean power over all non-DC frequencies:
/// about 1 for white noise, well below 1 for blue noise.
pub fn low_frequency_ratio(spectrum: &[f64], side: usize) -> f64 {
    let h = side as f64 / 2.0;
    let (mut low, mut nl, mut all, mut na) = (0.0, 0, 0.0, 0);
    for y in 0..side {
        for x in 0..side {
            let (dx, dy) = (x as f64 - h, y as f64 - h);
            let r = (dx * dx + dy * dy).sqrt();
            if r == 0.0 {
                continue;
            }
            all += spectrum[y * side + x];
            na += 1;
            if r <= side as f64 / 8.0 {
                low += spectrum[y * side + x];
                nl += 1;
            }
        }
    }
    (low / nl as f64) / (all / na as f64).max(1e-300)
}

/// What `mislab figure samplers` shows: `--spp` and `--seed`.
#[derive(Clone, Debug)]
pub struct Options {
    /// Points of one pixel drawn per panel (its samples at this spp).
    pub points: u32,
    /// Sample counts of the spectrum rows.
    pub spectrum_spp: Vec<u32>,
    /// Seed of the points and (shifted per seed) of the spectra.
    pub seed: u32,
}

impl Default for Options {
    /// The published figure: 256 points, spectra at 1 and 4 spp, seed 0.
    fn default() -> Self {
        Options { points: POINTS, spectrum_spp: SPECTRUM_SPP.to_vec(), seed: 0 }
    }
}

impl Options {
    /// `--spp N`: N points per panel and spectra at 1 and N spp (N ≤ 1024: the spectra are computed on the CPU).
    pub fn with_spp(spp: u32, seed: u32) -> Result<Options, LabError> {
        if !(1..=1024).contains(&spp) {
            return Err(LabError::Input(format!("--spp {spp}: figure samplers shows 1 to 1024 samples per pixel")));
        }
        let spectrum_spp = if spp == 1 { vec![1] } else { vec![1, spp] };
        Ok(Options { points: spp, spectrum_spp, seed })
    }
}

struct SamplerFigure {
    /// Per sampler: its point count (fixed-count samplers may round it) and the two point sets.
    points: Vec<(u32, Vec<[f32; 2]>, Vec<[f32; 2]>)>,
    spectra: Vec<Vec<(Vec<f64>, usize, f64)>>,
    spectrum_spp: Vec<u32>,
    spectrum_range: (f64, f64),
    points_title: u32,
}

fn point_color(i: usize) -> RGBColor {
    if i < 16 {
        RGBColor(213, 94, 0)
    } else if i < 64 {
        RGBColor(0, 158, 115)
    } else {
        RGBColor(0, 114, 178)
    }
}

impl Figure for SamplerFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), LabError> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| LabError::Plot(e.to_string());
        root.fill(&WHITE).map_err(err)?;
        let titled = root
            .titled(
                &format!(
                    "Samplers: first {} points of one pixel (orange 1–16, green 17–64, blue 65–) and error power spectra",
                    self.points_title
                ),
                ("sans-serif", 18),
            )
            .map_err(err)?;
        let cols = SamplerKind::ALL.len();
        let rows = 2 + self.spectrum_spp.len();
        let cells = titled.split_evenly((rows, cols));
        let row_names = ["jitter (0, 1)".to_string(), "light sample (dims 5, 6)".to_string()]
            .into_iter()
            .chain(self.spectrum_spp.iter().map(|n| format!("error power spectrum, {n} spp")))
            .collect::<Vec<_>>();
        for (c, kind) in SamplerKind::ALL.iter().enumerate() {
            for r in 0..rows {
                let area = &cells[r * cols + c];
                let (aw, ah) = area.dim_in_pixel();
                let side = (aw.min(ah.saturating_sub(36)) as f64 - 8.0).max(8.0);
                let x0 = (aw as f64 - side) / 2.0;
                let y0 = 20.0;
                let caption = match r {
                    0 if self.points[c].0 != self.points_title => {
                        format!("{} ({} points): {}", kind.name(), self.points[c].0, row_names[r])
                    }
                    0 => format!("{}: {}", kind.name(), row_names[r]),
                    _ => row_names[r].clone(),
                };
                area.draw(&Text::new(caption, (x0 as i32, 2), ("sans-serif", 12))).map_err(err)?;
                let frame = Rectangle::new(
                    [(x0 as i32, y0 as i32), ((x0 + side) as i32, (y0 + side) as i32)],
                    BLACK.stroke_width(1),
                );
                if r < 2 {
                    let pts = if r == 0 { &self.points[c].1 } else { &self.points[c].2 };
                    for (i, p) in pts.iter().enumerate() {
                        let (px, py) = (x0 + p[0] as f64 * side, y0 + (1.0 - p[1] as f64) * side);
                        area.draw(&Circle::new(
                            (px as i32, py as i32),
                            if i < 16 { 3 } else { 2 },
                            point_color(i).filled(),
                        ))
                        .map_err(err)?;
                    }
                } else {
                    let (img, n, ratio) = &self.spectra[c][r - 2];
                    let cw = side / *n as f64;
                    for y in 0..*n {
                        for x in 0..*n {
                            let v = img[y * n + x].max(1e-30).log10();
                            let t = (v - self.spectrum_range.0) / (self.spectrum_range.1 - self.spectrum_range.0);
                            let (px, py) = (x0 + x as f64 * cw, y0 + y as f64 * cw);
                            area.draw(&Rectangle::new(
                                [(px as i32, py as i32), ((px + cw).ceil() as i32, (py + cw).ceil() as i32)],
                                plot::colormap(t).filled(),
                            ))
                            .map_err(err)?;
                        }
                    }
                    area.draw(&Text::new(
                        format!("low-frequency power {ratio:.2}× mean"),
                        (x0 as i32, (y0 + side) as i32 + 2),
                        ("sans-serif", 11),
                    ))
                    .map_err(err)?;
                }
                area.draw(&frame).map_err(err)?;
            }
        }
        Ok(())
    }
}

/// Renders the published figure to `output` (.png or .svg) at `width`×`height` pixels.
pub fn run(output: &Path, width: u32, height: u32) -> Result<(), LabError> {
    run_with(output, width, height, &Options::default())
}

/// Renders the figure with `options` to `output` (.png or .svg) at `width`×`height` pixels.
pub fn run_with(output: &Path, width: u32, height: u32, options: &Options) -> Result<(), LabError> {
    let ext = output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if ext != "png" && ext != "svg" {
        return Err(LabError::Input(format!("{}: the figure is written as .png or .svg", output.display())));
    }
    if !(200..=16384).contains(&width) || !(200..=16384).contains(&height) {
        return Err(LabError::Input(format!("figure size {width}x{height} is out of range (200..=16384 per side)")));
    }
    // SVG gets coarser spectra: one rectangle element per cell.
    let cells = if ext == "svg" { 32 } else { SPECTRUM_SIZE };
    let mut points = vec![];
    let mut spectra = vec![];
    let mut white = 0.0;
    for kind in SamplerKind::ALL {
        // Fixed-count samplers build their points for the count (stratified rounds it to a grid it fits).
        let n = samplers::check_spp(*kind, options.points)?;
        let p = SamplerParams { kind: *kind, seed: 7u32.wrapping_add(options.seed), sampler_spp: n, width: 64 };
        let pixel = 2021;
        let jitter = (0..n).map(|i| samplers::sample_2d(&p, pixel, i, 0)).collect();
        let light = (0..n).map(|i| samplers::sample_2d(&p, pixel, i, DIMS_CAMERA + 1)).collect();
        points.push((n, jitter, light));
        let mut row = vec![];
        for (k, &spp) in options.spectrum_spp.iter().enumerate() {
            let spp = samplers::check_spp(*kind, spp)?;
            let (s, _) = error_spectrum_seeded(*kind, spp, options.seed);
            let ratio = low_frequency_ratio(&s, SPECTRUM_SIZE);
            if *kind == SamplerKind::Independent && k == 0 {
                // Normalise every panel to the white-noise level of independent sampling at 1 spp.
                let n = s.len() as f64;
                white = s.iter().sum::<f64>() / n;
            }
            let (d, n, _) = plot::downsample(&s, SPECTRUM_SIZE, SPECTRUM_SIZE, cells);
            row.push((d, n, ratio));
        }
        spectra.push(row);
    }
    for row in &mut spectra {
        for (img, _, _) in row.iter_mut() {
            img.iter_mut().for_each(|v| *v /= white.max(1e-300));
        }
    }
    let fig = SamplerFigure {
        points,
        spectra,
        spectrum_spp: options.spectrum_spp.clone(),
        spectrum_range: (-2.5, 0.5),
        points_title: options.points,
    };
    if ext == "svg" {
        plot::save_svg(output, (width, height), &fig)
    } else {
        plot::save_png(output, (width, height), &fig)
    }
}
