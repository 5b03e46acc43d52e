//! The lecture's figures, reproduced by one command: `mislab figure veach|area-vs-cosine -o OUT.png` renders
//! the panels at equal samples per pixel, side by side, each labelled (a built-in 5×7 bitmap font, no font files).
//!
//! - `veach`: Veach's plates (thesis fig. 9.2) under light sampling, BSDF sampling, and MIS with the balance
//!   and the power heuristic — light sampling is noisy on the sharp plates under the large lights, BSDF
//!   sampling on the rough plates under the small lights, MIS is good everywhere.
//! - `area-vs-cosine`: the lecture's slides of a floor under a low area light — light sampling by area (noisy
//!   near the light: the r⁻² term), cosine sampling (noisy far from it: the light's small solid angle), and MIS.
//! - `samplers`: each sequence's 2D points and error power spectrum at low spp (`sampler_figure`).
//! - `many-lights`: the Veach scene with its lights as 80,640 triangles (`veach-mis-triangles`) under MIS with
//!   uniform, power, light-tree, RIS and tree-candidate RIS light selection, at equal time (`--time` per panel, default 4 s): which
//!   light a sample picks decides the noise.

use crate::api;
use crate::lab::LabError;
use crate::render::film::Tonemap;
use crate::render::settings::{Heuristic, LightSampling, LightSelect, Settings, Strategy};
use std::path::PathBuf;

/// `mislab figure WHICH -o OUT.png`: one of the lecture's figures as a labelled PNG.
#[derive(clap::Args, Clone, Debug)]
pub struct FigureArgs {
    /// Which figure: veach (light / BSDF / balance / power on Veach's plates), area-vs-cosine (area / cosine / MIS)
    /// or samplers (each sequence's points and error spectrum).
    pub which: String,
    /// Output PNG.
    #[arg(short, long, default_value = "figure.png")]
    pub output: PathBuf,
    /// Samples per pixel of every panel (the same for all, as in the lecture; default 64). For samplers: the points
    /// drawn per panel and the second spectrum row's spp (default 256 points, spectra at 1 and 4 spp).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Width of one panel in pixels.
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    /// Height of one panel in pixels.
    #[arg(long, default_value_t = 256)]
    pub height: u32,
    /// Seed of every random number (the same for every panel; samplers: of the points and spectra).
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Seconds of rendering per panel, instead of --spp (the many-lights figure compares at equal time: 4 s
    /// unless given).
    #[arg(long)]
    pub time: Option<f64>,
}

/// Names accepted by `FigureArgs::which`.
pub const FIGURES: &[&str] = &["veach", "area-vs-cosine", "samplers", "many-lights"];

/// Gap between panels, pixels.
const GAP: u32 = 4;

/// One panel: its label and settings.
#[derive(Debug)]
struct Panel {
    label: &'static str,
    settings: Settings,
}

/// The scene, the grid (columns) and the panels of a figure.
fn layout(which: &str, base: &Settings) -> Result<(&'static str, u32, Vec<Panel>), LabError> {
    let with = |strategy: Strategy| Settings { strategy, ..base.clone() };
    match which {
        "veach" => Ok((
            "veach-mis",
            2,
            vec![
                Panel { label: "light sampling", settings: with(Strategy::Light) },
                Panel { label: "BSDF sampling", settings: with(Strategy::Bsdf) },
                Panel {
                    label: "MIS, balance",
                    settings: Settings { heuristic: Heuristic::Balance, ..with(Strategy::Mis) },
                },
                Panel {
                    label: "MIS, power",
                    settings: Settings { heuristic: Heuristic::Power, ..with(Strategy::Mis) },
                },
            ],
        )),
        "area-vs-cosine" => Ok((
            "area-vs-cosine",
            3,
            vec![
                Panel {
                    label: "area sampling",
                    settings: Settings { light_sampling: LightSampling::Area, ..with(Strategy::Light) },
                },
                Panel { label: "cosine sampling", settings: with(Strategy::Cosine) },
                Panel { label: "MIS", settings: with(Strategy::Mis) },
            ],
        )),
        "many-lights" => Ok((
            "veach-mis-triangles",
            3,
            [
                (LightSelect::Uniform, "uniform"),
                (LightSelect::Power, "power"),
                (LightSelect::Tree, "light tree"),
                (LightSelect::Ris, "RIS, M=2"),
                (LightSelect::TreeRis, "tree + RIS, M=2"),
            ]
            .into_iter()
            // tree-ris with M = 2: each candidate costs a walk down the 80,640-light tree (docs/estimators.md).
            .map(|(light_select, label)| Panel {
                label,
                settings: Settings { light_select, ris_candidates: 2, ..with(Strategy::Mis) },
            })
            .collect(),
        )),
        "samplers" => Err(LabError::Input(
            "figure 'samplers' is drawn from the samplers' CPU twins, not rendered in panels".into(),
        )),
        other => Err(LabError::Input(format!("unknown figure '{other}' (expected one of: {})", FIGURES.join(", ")))),
    }
}

/// Renders the figure `args.which` and writes it to `args.output` (PNG).
pub fn run(args: &FigureArgs) -> Result<(), LabError> {
    if args.which == "samplers" {
        // One column per sampler, four rows (two point sets, two spectra), each about a panel in size.
        let options = match args.spp {
            Some(n) => crate::lab::sampler_figure::Options::with_spp(n, args.seed)?,
            None => crate::lab::sampler_figure::Options { seed: args.seed, ..Default::default() },
        };
        let (w, h) = ((args.width * 6).clamp(200, 16384), (args.height * 4).clamp(200, 16384));
        crate::lab::sampler_figure::run_with(&args.output, w, h, &options)?;
        // Say what was written: a silent success reads like nothing happened.
        eprintln!(
            "wrote {} ({w}x{h}: {} points per sampler, spectra at {:?} spp, seed {})",
            args.output.display(),
            options.points,
            options.spectrum_spp,
            options.seed
        );
        return Ok(());
    }
    let ext = args.output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("png") {
        return Err(LabError::Input(format!(
            "{}: figures are written as PNG (use a .png name)",
            args.output.display()
        )));
    }
    let spp = args.spp.unwrap_or(64);
    if spp == 0 {
        return Err(LabError::Input("--spp must be at least 1".into()));
    }
    let time = args.time.or((args.which == "many-lights").then_some(4.0));
    if let Some(t) = time {
        if !(t.is_finite() && t > 0.0 && t <= 3600.0) {
            return Err(LabError::Input(format!("--time {t} must be a number of seconds in (0, 3600]")));
        }
    }
    let base = Settings { width: args.width, height: args.height, seed: args.seed, ..Settings::default() };
    let (scene_name, columns, panels) = layout(&args.which, &base)?;
    base.validate()?;
    let lab = api::Lab::open().map_err(|e| LabError::Input(format!("no usable GPU adapter: {e}")))?;
    let scene = api::SceneHandle::named(scene_name)?;
    let mut images = Vec::new();
    for p in &panels {
        let budget = match time {
            Some(t) => api::Budget::Time(std::time::Duration::from_secs_f64(t)),
            None => api::Budget::Samples(spp),
        };
        let mut job = api::Job::of(p.settings.clone(), budget)?;
        // At equal time, the first pass is timed apart from the pipeline's compilation (start-up is not counted).
        let image = api::render(&lab, &scene, &mut job, &mut api::Unobserved)?;
        let mut img = image.film.to_rgb8(p.settings.exposure, Tonemap::Clamp);
        let scale = if args.width >= 192 { 2 } else { 1 };
        draw_label(&mut img, 4, 4, p.label, scale);
        let budget = match time {
            Some(t) => format!("{t} s: {} spp", image.spp()),
            None => format!("{spp} spp"),
        };
        draw_label(&mut img, 4, 4 + 9 * scale, &budget, scale);
        images.push(img);
    }
    let rows = (images.len() as u32).div_ceil(columns);
    let mut out = image::RgbImage::from_pixel(
        columns * args.width + (columns - 1) * GAP,
        rows * args.height + (rows - 1) * GAP,
        image::Rgb([255, 255, 255]),
    );
    for (k, img) in images.iter().enumerate() {
        let (cx, cy) = (k as u32 % columns, k as u32 / columns);
        image::imageops::replace(&mut out, img, (cx * (args.width + GAP)) as i64, (cy * (args.height + GAP)) as i64);
    }
    save_png(&out, &args.output)?;
    let budget = match time {
        Some(t) => format!("{t} s per panel"),
        None => format!("{spp} spp per panel"),
    };
    eprintln!(
        "wrote {} ({}x{}: {} panels of {} at {budget}, seed {})",
        args.output.display(),
        out.width(),
        out.height(),
        panels.len(),
        scene_name,
        args.seed
    );
    Ok(())
}

/// Writes a PNG through a temporary file and a rename (no truncated figure after an interruption); a figure
/// whose every pixel is grey (both built-in figures) is stored as 8-bit greyscale, a third of the size.
fn save_png(img: &image::RgbImage, path: &std::path::Path) -> Result<(), LabError> {
    let grey = img.pixels().all(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2]);
    let write = |tmp: &std::path::Path| {
        let result = if grey {
            image::GrayImage::from_fn(img.width(), img.height(), |x, y| image::Luma([img.get_pixel(x, y).0[0]]))
                .save_with_format(tmp, image::ImageFormat::Png)
        } else {
            img.save_with_format(tmp, image::ImageFormat::Png)
        };
        result.map_err(LabError::from)
    };
    crate::io::output_file::replace_atomically(path, write)
        .map_err(|e| LabError::Input(format!("{}: could not write the figure: {e}", path.display())))
}

/// Draws `text` (upper-cased; characters without a glyph become blanks) at (x, y) in white on a darkened box,
/// each font pixel `scale`×`scale` image pixels. Clipped to the image.
pub fn draw_label(img: &mut image::RgbImage, x: u32, y: u32, text: &str, scale: u32) {
    let advance = 6 * scale;
    let (w, h) = (text.chars().count() as u32 * advance + 2 * scale, 9 * scale);
    for py in y..(y + h).min(img.height()) {
        for px in x..(x + w).min(img.width()) {
            let p = img.get_pixel_mut(px, py);
            p.0 = p.0.map(|c| c / 4);
        }
    }
    for (k, ch) in text.chars().enumerate() {
        let Some(rows) = glyph(ch.to_ascii_uppercase()) else { continue };
        for (r, row) in rows.iter().enumerate() {
            for (c, bit) in row.bytes().enumerate() {
                if bit != b'#' {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + scale + k as u32 * advance + c as u32 * scale + dx;
                        let py = y + scale + r as u32 * scale + dy;
                        if px < img.width() && py < img.height() {
                            img.put_pixel(px, py, image::Rgb([255, 255, 255]));
                        }
                    }
                }
            }
        }
    }
}

/// The 5×7 glyph of an upper-case letter, digit or a few punctuation marks; None for anything else.
fn glyph(c: char) -> Option<[&'static str; 7]> {
    Some(match c {
        'A' => [" ### ", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"],
        'B' => ["#### ", "#   #", "#   #", "#### ", "#   #", "#   #", "#### "],
        'C' => [" ### ", "#   #", "#    ", "#    ", "#    ", "#   #", " ### "],
        'D' => ["#### ", "#   #", "#   #", "#   #", "#   #", "#   #", "#### "],
        'E' => ["#####", "#    ", "#    ", "#### ", "#    ", "#    ", "#####"],
        'F' => ["#####", "#    ", "#    ", "#### ", "#    ", "#    ", "#    "],
        'G' => [" ### ", "#   #", "#    ", "# ###", "#   #", "#   #", " ####"],
        'H' => ["#   #", "#   #", "#   #", "#####", "#   #", "#   #", "#   #"],
        'I' => [" ### ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "],
        'J' => ["  ###", "   # ", "   # ", "   # ", "   # ", "#  # ", " ##  "],
        'K' => ["#   #", "#  # ", "# #  ", "##   ", "# #  ", "#  # ", "#   #"],
        'L' => ["#    ", "#    ", "#    ", "#    ", "#    ", "#    ", "#####"],
        'M' => ["#   #", "## ##", "# # #", "# # #", "#   #", "#   #", "#   #"],
        'N' => ["#   #", "#   #", "##  #", "# # #", "#  ##", "#   #", "#   #"],
        'O' => [" ### ", "#   #", "#   #", "#   #", "#   #", "#   #", " ### "],
        'P' => ["#### ", "#   #", "#   #", "#### ", "#    ", "#    ", "#    "],
        'Q' => [" ### ", "#   #", "#   #", "#   #", "# # #", "#  # ", " ## #"],
        'R' => ["#### ", "#   #", "#   #", "#### ", "# #  ", "#  # ", "#   #"],
        'S' => [" ####", "#    ", "#    ", " ### ", "    #", "    #", "#### "],
        'T' => ["#####", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  "],
        'U' => ["#   #", "#   #", "#   #", "#   #", "#   #", "#   #", " ### "],
        'V' => ["#   #", "#   #", "#   #", "#   #", "#   #", " # # ", "  #  "],
        'W' => ["#   #", "#   #", "#   #", "# # #", "# # #", "# # #", " # # "],
        'X' => ["#   #", "#   #", " # # ", "  #  ", " # # ", "#   #", "#   #"],
        'Y' => ["#   #", "#   #", " # # ", "  #  ", "  #  ", "  #  ", "  #  "],
        'Z' => ["#####", "    #", "   # ", "  #  ", " #   ", "#    ", "#####"],
        '0' => [" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "],
        '1' => ["  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "],
        '2' => [" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"],
        '3' => ["#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "],
        '4' => ["   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "],
        '5' => ["#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "],
        '6' => ["  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "],
        '7' => ["#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "],
        '8' => [" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "],
        '9' => [" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "],
        ' ' => ["     "; 7],
        '-' => ["     ", "     ", "     ", "#####", "     ", "     ", "     "],
        '.' => ["     ", "     ", "     ", "     ", "     ", " ##  ", " ##  "],
        ',' => ["     ", "     ", "     ", "     ", " ##  ", "  #  ", " #   "],
        ':' => ["     ", " ##  ", " ##  ", "     ", " ##  ", " ##  ", "     "],
        '/' => ["    #", "    #", "   # ", "  #  ", " #   ", "#    ", "#    "],
        '(' => ["   # ", "  #  ", " #   ", " #   ", " #   ", "  #  ", "   # "],
        ')' => [" #   ", "  #  ", "   # ", "   # ", "   # ", "  #  ", " #   "],
        '=' => ["     ", "     ", "#####", "     ", "#####", "     ", "     "],
        '+' => ["     ", "  #  ", "  #  ", "#####", "  #  ", "  #  ", "     "],
        '%' => ["##   ", "##  #", "   # ", "  #  ", " #   ", "#  ##", "   ##"],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_is_5_by_7() {
        for c in ('A'..='Z').chain('0'..='9').chain(" -.,:/()=+%".chars()) {
            let g = glyph(c).unwrap_or_else(|| panic!("no glyph for {c:?}"));
            assert!(g.iter().all(|r| r.len() == 5 && r.bytes().all(|b| b == b'#' || b == b' ')), "glyph {c:?}");
        }
    }

    #[test]
    fn labels_are_drawn_and_clipped() {
        let mut img = image::RgbImage::from_pixel(40, 12, image::Rgb([200, 200, 200]));
        draw_label(&mut img, 0, 0, "MIS 64 spp", 1);
        assert!(img.pixels().any(|p| p.0 == [255, 255, 255]), "text must be drawn");
        assert!(img.pixels().any(|p| p.0 == [50, 50, 50]), "the box behind it darkens the panel");
    }

    #[test]
    fn unknown_figures_are_errors() {
        let base = Settings::default();
        assert!(layout("nope", &base).unwrap_err().to_string().contains("expected one of"));
        assert!(layout("samplers", &base).unwrap_err().to_string().contains("not rendered in panels"));
        assert_eq!(layout("veach", &base).unwrap().2.len(), 4);
        assert_eq!(layout("area-vs-cosine", &base).unwrap().2.len(), 3);
    }
}
