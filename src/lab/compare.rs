//! `mislab compare A.exr B.exr`: how far an image is from a reference at the scale of blocks — the ratio of
//! image means (exposure / emitter-scale errors) and the relMSE of N×N-block means (where the light goes,
//! with the per-pixel noise averaged away), per channel. B is the reference.
//!
//! A may be an integer factor k smaller than B in both axes (a cheaper render of the same view): its blocks
//! are then N/k pixels wide, so each block covers the same part of the picture in both images.

use crate::lab::LabError;
use crate::testkit::metrics::RELMSE_EPSILON;
use std::path::{Path, PathBuf};

/// `mislab compare` flags.
#[derive(clap::Args, Clone, Debug)]
pub struct CompareArgs {
    /// The image to judge (EXR, linear radiance; or a render state).
    pub image: PathBuf,
    /// The reference (EXR, linear radiance; or a render state).
    pub reference: PathBuf,
    /// Block size N in pixels of the reference: relMSE of the N×N-block means.
    #[arg(long, default_value_t = 16)]
    pub block: u32,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write a side-by-side PNG (image left, reference right; sRGB, clamped, same exposure).
    #[arg(long, value_name = "PNG")]
    pub side_by_side: Option<PathBuf>,
    /// Width of each panel of --side-by-side in pixels (box-filtered down from the images); 0 = about 20,000
    /// pixels per panel (a noisy pair stays near 100 KB).
    #[arg(long, default_value_t = 0)]
    pub panel_width: u32,
    /// Exposure (stops) of --side-by-side.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
}

/// A linear RGB image, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGB.
    pub pixels: Vec<[f32; 3]>,
}

/// The result of a comparison; channel arrays are R, G, B.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Comparison {
    /// Mean of the image per channel.
    pub mean_image: [f64; 3],
    /// Mean of the reference per channel.
    pub mean_reference: [f64; 3],
    /// mean_image / mean_reference per channel.
    pub mean_ratio: [f64; 3],
    /// Ratio of the channel sums (the whole image's brightness).
    pub mean_ratio_all: f64,
    /// relMSE of the block means per channel: mean over blocks of (x − r)² / (r² + 0.01).
    pub block_relmse: [f64; 3],
    /// The mean of the three.
    pub block_relmse_all: f64,
    /// Block size in pixels of the image and of the reference.
    pub block_image: u32,
    /// Block size in pixels of the reference.
    pub block_reference: u32,
    /// Number of blocks (partial blocks at the right and bottom edges count, with their own pixel count).
    pub blocks: usize,
    /// Non-finite pixel values in the image and in the reference (they make the metrics non-finite).
    pub nonfinite: [usize; 2],
    /// Width and height of the image and of the reference.
    pub sizes: [[u32; 2]; 2],
}

/// Reads an EXR (or render state) as linear RGB.
pub fn read(path: &Path) -> Result<Image, LabError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("exr") | Some("state")) {
        // PNG holds tonemapped sRGB, not radiance: comparing it would measure the tonemapper.
        return Err(LabError::Input(format!(
            "{}: compare reads linear images (.exr, or a render .state)",
            path.display()
        )));
    }
    let r = crate::lab::reference::read_exr(path)?;
    if r.width == 0 || r.height == 0 {
        return Err(LabError::Input(format!("{}: empty image", path.display())));
    }
    Ok(Image { width: r.width, height: r.height, pixels: r.pixels })
}

/// Block means with `block`-pixel blocks: (means in row-major block order, blocks across, blocks down).
pub fn block_means(img: &Image, block: u32) -> (Vec<[f64; 3]>, u32, u32) {
    let (bw, bh) = (img.width.div_ceil(block), img.height.div_ceil(block));
    let mut sums = vec![[0.0f64; 4]; (bw * bh) as usize];
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.pixels[(y * img.width + x) as usize];
            let s = &mut sums[((y / block) * bw + x / block) as usize];
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
            s[3] += 1.0;
        }
    }
    (sums.iter().map(|s| [s[0] / s[3], s[1] / s[3], s[2] / s[3]]).collect(), bw, bh)
}

/// Compares `image` against `reference` with `block`-pixel blocks of the reference.
pub fn compare(image: &Image, reference: &Image, block: u32) -> Result<Comparison, LabError> {
    if block == 0 {
        return Err(LabError::Input("--block must be at least 1".into()));
    }
    // The image may be k times smaller than the reference (k an integer, the same in both axes).
    let k = reference.width / image.width.max(1);
    let same_view = k >= 1 && image.width * k == reference.width && image.height * k == reference.height;
    if !same_view {
        return Err(LabError::Input(format!(
            "sizes differ: the image is {}x{}, the reference {}x{} (the image may be smaller by one integer factor in both axes, no other difference)",
            image.width, image.height, reference.width, reference.height
        )));
    }
    if block % k != 0 {
        return Err(LabError::Input(format!(
            "--block {block} is not a multiple of the size factor {k} between the images"
        )));
    }
    let (mi, iw, ih) = block_means(image, block / k);
    let (mr, rw, rh) = block_means(reference, block);
    debug_assert_eq!((iw, ih), (rw, rh));
    let mean = |img: &Image| {
        let mut s = [0.0f64; 3];
        for p in &img.pixels {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
        s.map(|v| v / img.pixels.len() as f64)
    };
    let (mean_image, mean_reference) = (mean(image), mean(reference));
    let mut rel = [0.0f64; 3];
    for (x, r) in mi.iter().zip(&mr) {
        for c in 0..3 {
            rel[c] += (x[c] - r[c]).powi(2) / (r[c] * r[c] + RELMSE_EPSILON);
        }
    }
    let rel = rel.map(|v| v / mi.len() as f64);
    let nonfinite = |img: &Image| img.pixels.iter().flatten().filter(|v| !v.is_finite()).count();
    Ok(Comparison {
        mean_image,
        mean_reference,
        mean_ratio: [0, 1, 2].map(|c| mean_image[c] / mean_reference[c]),
        mean_ratio_all: mean_image.iter().sum::<f64>() / mean_reference.iter().sum::<f64>(),
        block_relmse: rel,
        block_relmse_all: rel.iter().sum::<f64>() / 3.0,
        block_image: block / k,
        block_reference: block,
        blocks: mi.len(),
        nonfinite: [nonfinite(image), nonfinite(reference)],
        sizes: [[image.width, image.height], [reference.width, reference.height]],
    })
}

/// The comparison as a small table.
pub fn table(c: &Comparison) -> String {
    let mut s = format!(
        "blocks: {} of {}x{} px (image) / {}x{} px (reference); relMSE = mean of (x - r)^2 / (r^2 + {RELMSE_EPSILON})\n",
        c.blocks, c.block_image, c.block_image, c.block_reference, c.block_reference
    );
    s += "channel  mean image  mean reference  ratio     block relMSE\n";
    for (c_i, name) in ["R", "G", "B"].iter().enumerate() {
        s += &format!(
            "{name:<8} {:<11.6} {:<15.6} {:<9.4} {:.3e}\n",
            c.mean_image[c_i], c.mean_reference[c_i], c.mean_ratio[c_i], c.block_relmse[c_i]
        );
    }
    s += &format!("all      {:<11} {:<15} {:<9.4} {:.3e}\n", "", "", c.mean_ratio_all, c.block_relmse_all);
    if c.nonfinite != [0, 0] {
        s += &format!("non-finite values: {} in the image, {} in the reference\n", c.nonfinite[0], c.nonfinite[1]);
    }
    s
}

/// Box-filters `img` down to `width` pixels across (never up), keeping the aspect ratio.
pub fn downscale(img: &Image, width: u32) -> Image {
    let width = width.clamp(1, img.width);
    let height = ((img.height as u64 * width as u64) / img.width as u64).max(1) as u32;
    let mut pixels = vec![[0.0f32; 3]; (width * height) as usize];
    for y in 0..height {
        let (y0, y1) = (y * img.height / height, ((y + 1) * img.height / height).max(y * img.height / height + 1));
        for x in 0..width {
            let (x0, x1) = (x * img.width / width, ((x + 1) * img.width / width).max(x * img.width / width + 1));
            let mut s = [0.0f64; 3];
            for sy in y0..y1 {
                for sx in x0..x1 {
                    let p = img.pixels[(sy * img.width + sx) as usize];
                    for c in 0..3 {
                        // A NaN or Inf would turn the whole output pixel black or white; count it as black.
                        s[c] += if p[c].is_finite() { p[c] as f64 } else { 0.0 };
                    }
                }
            }
            let n = ((y1 - y0) * (x1 - x0)) as f64;
            pixels[(y * width + x) as usize] = s.map(|v| (v / n) as f32);
        }
    }
    Image { width, height, pixels }
}

/// Writes image | reference side by side as sRGB PNG, each `panel_width` wide, with a 4-pixel gap.
pub fn write_side_by_side(
    path: &Path,
    image: &Image,
    reference: &Image,
    panel_width: u32,
    exposure: f32,
) -> Result<(), LabError> {
    let panel_width = match panel_width {
        0 => ((20_000.0 * image.width as f64 / image.height as f64).sqrt() as u32).max(1),
        w => w,
    };
    let (a, b) = (downscale(image, panel_width), downscale(reference, panel_width));
    let gap = 4;
    let (w, h) = (a.width + gap + b.width, a.height.max(b.height));
    let mut out = image::RgbImage::new(w, h);
    for (panel, x0) in [(&a, 0), (&b, a.width + gap)] {
        for y in 0..panel.height {
            for x in 0..panel.width {
                let p = panel.pixels[(y * panel.width + x) as usize];
                let v = p.map(|v| {
                    let t = crate::render::film::tonemap(v, exposure, crate::render::film::Tonemap::Clamp);
                    (crate::render::film::linear_to_srgb(t) * 255.0 + 0.5) as u8
                });
                out.put_pixel(x0 + x, y, image::Rgb(v));
            }
        }
    }
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    Ok(crate::io::output_file::check(path, true)?.write(|tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))?;
        let encoder =
            PngEncoder::new_with_quality(std::io::BufWriter::new(file), CompressionType::Best, FilterType::Adaptive);
        out.write_with_encoder(encoder).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))
    })?)
}

/// Runs `mislab compare`: prints the table (or JSON); bad or mismatched input is an error (exit 2).
pub fn run(args: &CompareArgs) -> Result<u8, LabError> {
    let image = read(&args.image)?;
    let reference = read(&args.reference)?;
    let c = compare(&image, &reference, args.block)
        .map_err(|e| LabError::Input(format!("{} vs {}: {e}", args.image.display(), args.reference.display())))?;
    if args.json {
        println!("{}", serde_json::to_string(&c).map_err(LabError::from)?);
    } else {
        print!("{}", table(&c));
    }
    if let Some(png) = &args.side_by_side {
        write_side_by_side(png, &image, &reference, args.panel_width, args.exposure)?;
        eprintln!("wrote {}", png.display());
    }
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(w: u32, h: u32, v: [f32; 3]) -> Image {
        Image { width: w, height: h, pixels: vec![v; (w * h) as usize] }
    }

    #[test]
    fn identical_images_give_ratio_one_and_zero_error() {
        let img = Image {
            width: 37,
            height: 21,
            pixels: (0..37 * 21).map(|i| [i as f32 * 0.01, 0.5, (i % 7) as f32]).collect(),
        };
        let c = compare(&img, &img, 16).unwrap();
        assert_eq!(c.mean_ratio, [1.0, 1.0, 1.0]);
        assert_eq!(c.block_relmse_all, 0.0);
        // 37 × 21 with 16-pixel blocks: 3 × 2 blocks, the edge ones partial.
        assert_eq!(c.blocks, 6);
    }

    #[test]
    fn a_scaled_image_has_the_scale_as_mean_ratio_and_the_analytic_relmse() {
        let r = constant(32, 32, [1.0, 0.5, 0.0]);
        let x = constant(32, 32, [2.0, 0.5, 0.1]);
        let c = compare(&x, &r, 8).unwrap();
        assert!((c.mean_ratio[0] - 2.0).abs() < 1e-12);
        assert!((c.mean_ratio[1] - 1.0).abs() < 1e-12);
        assert!(c.mean_ratio[2].is_infinite());
        // (2 − 1)² / (1 + 0.01); 0; 0.1² / 0.01.
        assert!((c.block_relmse[0] - 1.0 / 1.01).abs() < 1e-9);
        assert_eq!(c.block_relmse[1], 0.0);
        assert!((c.block_relmse[2] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn block_means_average_noise_away_but_not_structure() {
        // A checkerboard of 0 and 2 at pixel scale has block means of exactly 1: no block error against 1.
        let w = 16;
        let checker = Image {
            width: w,
            height: w,
            pixels: (0..w * w).map(|i| if (i % w + i / w) % 2 == 0 { [0.0; 3] } else { [2.0; 3] }).collect(),
        };
        let flat = constant(w, w, [1.0; 3]);
        assert_eq!(compare(&checker, &flat, 4).unwrap().block_relmse_all, 0.0);
        assert!(compare(&checker, &flat, 1).unwrap().block_relmse_all > 0.9);
        // Light moved from the left half to the right half keeps the mean but not the block means.
        let left = Image {
            width: w,
            height: w,
            pixels: (0..w * w).map(|i| if i % w < w / 2 { [2.0; 3] } else { [0.0; 3] }).collect(),
        };
        let c = compare(&left, &flat, 4).unwrap();
        assert!((c.mean_ratio_all - 1.0).abs() < 1e-12);
        assert!((c.block_relmse_all - 1.0 / 1.01).abs() < 1e-9);
    }

    #[test]
    fn a_smaller_image_is_compared_with_scaled_blocks() {
        // The reference at 64², the image its 2× box-downscaled version: the same block means.
        let r = Image {
            width: 64,
            height: 64,
            pixels: (0..64 * 64).map(|i| [((i % 64) / 8) as f32, ((i / 64) / 4) as f32, 1.0]).collect(),
        };
        let small = downscale(&r, 32);
        assert_eq!((small.width, small.height), (32, 32));
        let c = compare(&small, &r, 16).unwrap();
        assert_eq!((c.block_image, c.block_reference, c.blocks), (8, 16, 16));
        assert!(c.block_relmse_all < 1e-12, "{}", c.block_relmse_all);
        assert!(compare(&small, &r, 15).unwrap_err().to_string().contains("multiple"));
    }

    #[test]
    fn size_mismatches_and_bad_files_are_errors() {
        let e = compare(&constant(30, 20, [1.0; 3]), &constant(64, 40, [1.0; 3]), 16).unwrap_err();
        assert!(e.to_string().contains("sizes differ"), "{e}");
        // Twice as wide but not twice as high: not the same view.
        assert!(compare(&constant(32, 32, [1.0; 3]), &constant(64, 40, [1.0; 3]), 16).is_err());
        assert!(compare(&constant(64, 40, [1.0; 3]), &constant(32, 20, [1.0; 3]), 16).is_err());
        assert!(compare(&constant(4, 4, [1.0; 3]), &constant(4, 4, [1.0; 3]), 0).is_err());
        let dir = std::env::temp_dir().join(format!("mislab-compare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let junk = dir.join("junk.exr");
        std::fs::write(&junk, b"not an exr").unwrap();
        assert!(read(&junk).unwrap_err().to_string().contains("junk.exr"));
        assert!(read(&dir.join("missing.exr")).unwrap_err().to_string().contains("missing.exr"));
        assert!(read(&dir.join("render.png")).unwrap_err().to_string().contains("linear"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn non_finite_pixels_are_counted_and_poison_the_metrics() {
        let r = constant(8, 8, [1.0; 3]);
        let mut x = r.clone();
        x.pixels[5][1] = f32::NAN;
        let c = compare(&x, &r, 4).unwrap();
        assert_eq!(c.nonfinite, [1, 0]);
        assert!(c.block_relmse[1].is_nan() && c.block_relmse[0] == 0.0);
    }

    #[test]
    fn side_by_side_png_holds_both_panels() {
        let dir = std::env::temp_dir().join(format!("mislab-sbs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("sbs.png");
        write_side_by_side(&png, &constant(64, 32, [1.0; 3]), &constant(64, 32, [0.0; 3]), 32, 0.0).unwrap();
        let img = image::open(&png).unwrap().into_rgb8();
        assert_eq!(img.dimensions(), (32 + 4 + 32, 16));
        assert_eq!(img.get_pixel(0, 0).0, [255; 3]);
        assert_eq!(img.get_pixel(67, 15).0, [0; 3]);
        std::fs::remove_dir_all(&dir).ok();
    }
}
