//! Image textures for the importers: PFM (our reader), TGA / PNG / JPEG / EXR (the image crate, under
//! `image::Limits`: a header's declared size is checked before anything is allocated), loaded once per (file,
//! encoding) into [`Scene::textures`]. Float images are stored sRGB-encoded in 8 bits like the rest.

use super::{read_input::read_bytes, Scene, SceneError, Texture, TextureKind, Wrap};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Textures already loaded, by file and sRGB flag; checkerboards already made, by their colours' bits.
#[derive(Default)]
pub struct TextureCache {
    loaded: HashMap<(PathBuf, bool), u32>,
    checkerboards: HashMap<[u32; 6], u32>,
}

impl TextureCache {
    /// The index in `scene.textures` of `file` (loading it the first time); `referenced_by` (`scene.pbrt: line
    /// 12`) is named in its errors.
    pub fn load(&mut self, file: &Path, srgb: bool, referenced_by: &str, scene: &mut Scene) -> Result<u32, SceneError> {
        if let Some(&i) = self.loaded.get(&(file.to_path_buf(), srgb)) {
            return Ok(i);
        }
        let (width, height, texels) = load_rgba8(file, srgb, referenced_by)?;
        let name = file.display().to_string();
        let index = scene.textures.len() as u32;
        scene.textures.push(Texture {
            name,
            width,
            height,
            texels,
            srgb,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            nearest: false,
            kind: TextureKind::Image,
        });
        self.loaded.insert((file.to_path_buf(), srgb), index);
        Ok(index)
    }

    /// The index in `scene.textures` of a checkerboard of `tex1` (even checks) and `tex2` (odd), made once.
    pub fn checkerboard(&mut self, tex1: glam::Vec3, tex2: glam::Vec3, scene: &mut Scene) -> u32 {
        let mut key = [0u32; 6];
        for (k, v) in key.iter_mut().zip(tex1.to_array().iter().chain(&tex2.to_array())) {
            *k = v.to_bits();
        }
        *self.checkerboards.entry(key).or_insert_with(|| {
            scene.textures.push(Texture {
                name: format!("checkerboard {tex1} / {tex2}"),
                width: 0,
                height: 0,
                texels: vec![],
                srgb: false,
                wrap_s: Wrap::Repeat,
                wrap_t: Wrap::Repeat,
                nearest: false,
                kind: TextureKind::Checkerboard { tex1, tex2 },
            });
            scene.textures.len() as u32 - 1
        })
    }
}

/// Most texels an imported texture may have on a side (the device's 2D texture limit is not the bound here: the
/// texels go into storage buffers, and 16384² RGBA8 is already 1 GiB).
pub const MAX_TEXTURE_SIDE: u32 = 16384;
/// Most bytes an image decoder may allocate for one texture (the image crate's own default cap).
pub const MAX_DECODED_BYTES: u64 = 512 << 20;

/// Decodes `bytes` as `format` through the image crate, checking the size the header declares (at most
/// `MAX_TEXTURE_SIDE` on a side, `MAX_DECODED_BYTES` decoded) before any texel is allocated; a decoder panic is an
/// error too. The message is the problem alone (the caller names the file).
pub fn decode_limited(bytes: &[u8], format: image::ImageFormat) -> Result<image::DynamicImage, String> {
    let name = format.extensions_str().first().map_or("image".to_string(), |e| e.to_ascii_uppercase());
    let decoded = super::catch_quietly(|| {
        let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_DECODED_BYTES);
        reader.limits(limits);
        let decoder = reader.into_decoder().map_err(|e| describe(&e, &name))?;
        let (w, h) = image::ImageDecoder::dimensions(&decoder);
        if w == 0 || h == 0 {
            return Err(format!("{name} image {w}×{h} is empty"));
        }
        if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
            return Err(format!("{name} image {w}×{h} is too large (at most {MAX_TEXTURE_SIDE} texels on a side)"));
        }
        let need = image::ImageDecoder::total_bytes(&decoder);
        if need > MAX_DECODED_BYTES {
            return Err(format!(
                "{name} image {w}×{h} needs {} MiB to decode, over the limit of {} MiB",
                need >> 20,
                MAX_DECODED_BYTES >> 20
            ));
        }
        image::DynamicImage::from_decoder(decoder).map_err(|e| describe(&e, &name))
    });
    decoded.map_err(|p| format!("corrupt {name} image (the decoder failed: {p})"))?
}

/// A decoder error as a sentence.
fn describe(e: &image::ImageError, name: &str) -> String {
    match e {
        image::ImageError::Limits(l) => format!("{name} image is too large to decode ({l})"),
        image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            format!("truncated {name} image ({e})")
        }
        image::ImageError::Unsupported(_) => format!("unsupported {name} variant: {e}"),
        _ => format!("cannot decode {name} image: {e}"),
    }
}

/// Decodes an image file to RGBA8, top row first. Float formats are encoded to sRGB 8-bit when `srgb`. Errors name
/// the file and `referenced_by` (`scene.pbrt: line 12`, or empty).
pub fn load_rgba8(file: &Path, srgb: bool, referenced_by: &str) -> Result<(u32, u32, Vec<[u8; 4]>), SceneError> {
    let bytes = read_bytes(file, referenced_by)?;
    let ext = file.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let by = super::read_input::by(referenced_by);
    let bad = |m: String| SceneError::new(file, format!("{m}{by}"));
    let encode = |v: f32| {
        let v = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
        let e = if srgb {
            if v <= 0.0031308 {
                12.92 * v
            } else {
                1.055 * v.powf(1.0 / 2.4) - 0.055
            }
        } else {
            v
        };
        (e * 255.0 + 0.5) as u8
    };
    let format = match ext.as_str() {
        "pfm" => {
            let p = super::pfm::decode(&bytes).map_err(bad)?;
            let texels = p.texels.iter().map(|c| [encode(c[0]), encode(c[1]), encode(c[2]), 255]).collect();
            return Ok((p.width, p.height, texels));
        }
        "tga" => image::ImageFormat::Tga,
        "png" => image::ImageFormat::Png,
        "jpg" | "jpeg" => image::ImageFormat::Jpeg,
        "exr" => image::ImageFormat::OpenExr,
        _ => {
            return Err(bad(format!(
                "unsupported texture format '.{}' (expected .tga, .png, .jpg, .exr or .pfm)",
                crate::io::input_file::clip(&ext, 20)
            )))
        }
    };
    // A file whose content says what it is (PNG, JPEG and EXR have magic numbers; TGA has none) is read as that,
    // as the image crate's `load_from_memory` did before, whatever its extension.
    let format = match image::guess_format(&bytes) {
        Ok(f @ (image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::OpenExr)) => f,
        _ => format,
    };
    let decoded = decode_limited(&bytes, format).map_err(bad)?;
    if format == image::ImageFormat::OpenExr {
        let f = decoded.to_rgba32f();
        let texels = f.pixels().map(|p| [encode(p[0]), encode(p[1]), encode(p[2]), 255]).collect();
        Ok((f.width(), f.height(), texels))
    } else {
        let r = decoded.to_rgba8();
        Ok((r.width(), r.height(), r.pixels().map(|p| p.0).collect()))
    }
}
