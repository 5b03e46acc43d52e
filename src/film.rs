//! Film: the accumulated image on the CPU — per-pixel mean, variance and counts — and its output as
//! PNG (tonemapped, sRGB) or EXR (linear float32 RGB, raw radiance).

use crate::gpu_types::GpuAccum;
use std::path::Path;

/// The image as accumulated: mean radiance, per-channel sum of squared deviations, sample counts.
#[derive(Clone, Debug)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Mean radiance per pixel, row-major from the top.
    pub mean: Vec<[f32; 3]>,
    /// Sum of squared deviations per pixel and channel (variance = m2 / (n − 1)).
    pub m2: Vec<[f32; 3]>,
    /// Finite samples per pixel.
    pub count: Vec<u32>,
    /// Non-finite samples per pixel (counted, not accumulated).
    pub nonfinite: Vec<u32>,
    /// Non-finite samples over the whole render (the device counter).
    pub nonfinite_total: u64,
}

/// How linear radiance becomes display values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
pub enum Tonemap {
    /// Scale by 2^exposure and clamp to [0, 1].
    #[default]
    Clamp,
    /// ACES filmic curve (Narkowicz 2015 fit).
    Aces,
}

/// Linear → sRGB transfer function.
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.0031308 {
        12.92 * x.max(0.0)
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Applies exposure and a tonemapper to one linear value, giving [0, 1] linear display radiance.
pub fn tonemap(x: f32, exposure: f32, op: Tonemap) -> f32 {
    let v = x * exposure.exp2();
    let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
    match op {
        Tonemap::Clamp => v.min(1.0),
        Tonemap::Aces => ((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14)).clamp(0.0, 1.0),
    }
}

impl Film {
    /// Builds a film from the device's accumulators.
    pub fn from_accum(width: u32, height: u32, accum: &[GpuAccum], nonfinite_total: u64) -> Film {
        Film {
            width,
            height,
            mean: accum.iter().map(|a| a.mean).collect(),
            m2: accum.iter().map(|a| a.m2).collect(),
            count: accum.iter().map(|a| a.count).collect(),
            nonfinite: accum.iter().map(|a| a.nonfinite).collect(),
            nonfinite_total,
        }
    }

    /// Mean over all pixels and channels.
    pub fn mean_value(&self) -> f64 {
        let s: f64 = self.mean.iter().map(|c| c.iter().map(|&v| v as f64).sum::<f64>()).sum();
        s / (3.0 * self.mean.len().max(1) as f64)
    }

    /// Per-channel variance of the pixel mean (sample variance / n), or None with fewer than 2 samples.
    pub fn variance_of_mean(&self, i: usize) -> Option<[f64; 3]> {
        let n = self.count[i] as f64;
        if n < 2.0 {
            return None;
        }
        Some(self.m2[i].map(|m| m as f64 / (n - 1.0) / n))
    }

    /// Samples per pixel (the minimum over pixels; all pixels get the same count unless samples were
    /// non-finite).
    pub fn spp(&self) -> u32 {
        self.count.iter().zip(&self.nonfinite).map(|(c, b)| c + b).min().unwrap_or(0)
    }

    /// Whether every pixel holds `spp` samples (accumulated or counted as non-finite): lavapipe's loop budget can
    /// cut a dispatch short without an error.
    pub fn is_complete(&self, spp: u32) -> bool {
        self.count.iter().zip(&self.nonfinite).all(|(c, b)| c + b == spp)
    }

    /// 8-bit sRGB pixels after exposure and tonemapping.
    pub fn to_rgb8(&self, exposure: f32, op: Tonemap) -> image::RgbImage {
        let mut img = image::RgbImage::new(self.width, self.height);
        for (i, p) in img.pixels_mut().enumerate() {
            let c = self.mean[i];
            *p = image::Rgb(c.map(|v| (linear_to_srgb(tonemap(v, exposure, op)) * 255.0 + 0.5) as u8));
        }
        img
    }

    /// Linear float RGB (raw radiance).
    pub fn to_rgb32f(&self) -> image::Rgb32FImage {
        let data: Vec<f32> = self.mean.iter().flat_map(|c| *c).collect();
        image::Rgb32FImage::from_raw(self.width, self.height, data).expect("film size matches its data")
    }

    /// Writes PNG (tonemapped) or EXR (linear) by the extension of `path`. Writes to a temporary file
    /// first and renames it, so an interrupted write never leaves a truncated image behind.
    pub fn save(&self, path: &Path, exposure: f32, op: Tonemap) -> Result<(), String> {
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
        let tmp = path.with_extension(format!("{ext}.partial"));
        let result = match ext.as_str() {
            "png" => self.to_rgb8(exposure, op).save_with_format(&tmp, image::ImageFormat::Png),
            "exr" => self.to_rgb32f().save_with_format(&tmp, image::ImageFormat::OpenExr),
            _ => return Err(format!("{}: unknown output format '.{ext}' (use .png or .exr)", path.display())),
        };
        result.map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("{}: could not write the image: {e}", path.display())
        })?;
        std::fs::rename(&tmp, path).map_err(|e| format!("{}: could not write the image: {e}", path.display()))
    }
}
