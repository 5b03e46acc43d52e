//! Film: the accumulated image on the CPU — per-pixel mean, variance and counts — and its output as
//! PNG (tonemapped, sRGB) or EXR (linear float32 RGB, raw radiance).

use crate::gpu::types::GpuAccum;
use crate::render::RenderError;
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
    // Overflow to +inf is a very bright pixel (white), not a missing one; only NaN is black.
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, f32::MAX) };
    match op {
        Tonemap::Clamp => v.min(1.0),
        // The fit is within 1e-6 of its limit 2.51/2.43 (clamped to 1) long before 1e6; beyond, v² overflows.
        Tonemap::Aces => {
            let v = v.min(1e6);
            ((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14)).clamp(0.0, 1.0)
        }
    }
}

impl Film {
    /// The mean image, as the EXR writer takes it.
    pub fn pixels(&self) -> crate::io::exr_image::Pixels<'_> {
        crate::io::exr_image::Pixels { width: self.width, height: self.height, rgb: &self.mean }
    }

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

    /// Writes PNG (tonemapped) or EXR (linear) by the extension of `path`, replacing what is there (see
    /// `output_file`: through a temporary file and a rename; symlinks are written through).
    pub fn save(&self, path: &Path, exposure: f32, op: Tonemap) -> Result<(), RenderError> {
        self.save_to(&crate::io::output_file::check(path, true)?, exposure, op, &[])
    }

    /// Writes the image to a checked output, with `attributes` (spp, seed, scene, settings, ...) in its
    /// header: EXR text attributes, PNG tEXt chunks. A PNG also carries an sRGB chunk: its values are sRGB.
    pub fn save_to(
        &self,
        target: &crate::io::output_file::OutputTarget,
        exposure: f32,
        op: Tonemap,
        attributes: &[(String, String)],
    ) -> Result<(), RenderError> {
        let path = &target.given;
        let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
        match ext.as_str() {
            "png" => Ok(target.write(|tmp| write_png(tmp, &self.to_rgb8(exposure, op), attributes))?),
            "exr" => Ok(target.write(|tmp| crate::io::exr_image::encode(tmp, self.pixels(), attributes))?),
            _ => Err(RenderError::OutputFormat { path: path.clone(), ext }),
        }
    }
}

fn write_png(path: &Path, img: &image::RgbImage, attributes: &[(String, String)]) -> Result<(), png::EncodingError> {
    encode_png(std::io::BufWriter::new(std::fs::File::create(path)?), img, attributes)
}

impl Film {
    /// The image as the bytes of a file of `format` (`png`: tonemapped; `exr`: linear), with `attributes` in its
    /// header, for a caller that writes no file itself (a browser's download).
    pub fn encoded(
        &self,
        format: &str,
        exposure: f32,
        op: Tonemap,
        attributes: &[(String, String)],
    ) -> Result<Vec<u8>, String> {
        let mut bytes = std::io::Cursor::new(Vec::new());
        match format {
            "png" => encode_png(&mut bytes, &self.to_rgb8(exposure, op), attributes).map_err(|e| e.to_string())?,
            "exr" => {
                crate::io::exr_image::encode_into(&mut bytes, self.pixels(), attributes).map_err(|e| e.to_string())?
            }
            _ => return Err(format!("unknown image format '{format}' (png or exr)")),
        }
        Ok(bytes.into_inner())
    }
}

/// An 8-bit sRGB PNG with an sRGB chunk and one tEXt chunk per attribute.
fn encode_png(
    out: impl std::io::Write,
    img: &image::RgbImage,
    attributes: &[(String, String)],
) -> Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, img.width(), img.height());
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    for (k, v) in attributes {
        // tEXt is Latin-1: keep what fits.
        let v: String = v.chars().map(|c| if (c as u32) < 256 { c } else { '?' }).collect();
        encoder.add_text_chunk(k.clone(), v)?;
    }
    let mut writer = encoder.write_header()?;
    writer.write_image_data(img.as_raw())?;
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encoded_files_decode_to_the_film() {
        let accum: Vec<GpuAccum> = (0..6)
            .map(|i| GpuAccum { mean: [i as f32 * 0.25, 0.5, 2.0], count: 4, m2: [0.0; 3], nonfinite: 0 })
            .collect();
        let film = Film::from_accum(3, 2, &accum, 0);
        let attributes = [("spp".to_string(), "4".to_string())];
        let png = film.encoded("png", 0.0, Tonemap::Clamp, &attributes).unwrap();
        let decoded = image::load_from_memory_with_format(&png, image::ImageFormat::Png).unwrap().to_rgb8();
        assert_eq!(decoded, film.to_rgb8(0.0, Tonemap::Clamp));
        let exr = film.encoded("exr", 0.0, Tonemap::Clamp, &attributes).unwrap();
        let decoded = image::load_from_memory_with_format(&exr, image::ImageFormat::OpenExr).unwrap().to_rgb32f();
        let values: Vec<[f32; 3]> = decoded.pixels().map(|p| p.0).collect();
        assert_eq!(values, film.mean);
        assert!(film.encoded("jpg", 0.0, Tonemap::Clamp, &[]).is_err());
    }
}
