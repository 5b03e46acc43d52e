//! Image textures for the importers: TGA and PFM (our readers), PNG / JPEG / EXR (the image crate), loaded once
//! per (file, encoding) into [`Scene::textures`]. Float images are stored sRGB-encoded in 8 bits like the rest.

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
    /// The index in `scene.textures` of `file` (loading it the first time).
    pub fn load(&mut self, file: &Path, srgb: bool, scene: &mut Scene) -> Result<u32, SceneError> {
        if let Some(&i) = self.loaded.get(&(file.to_path_buf(), srgb)) {
            return Ok(i);
        }
        let (width, height, texels) = load_rgba8(file, srgb)?;
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

/// Decodes an image file to RGBA8, top row first. Float formats are encoded to sRGB 8-bit when `srgb`.
pub fn load_rgba8(file: &Path, srgb: bool) -> Result<(u32, u32, Vec<[u8; 4]>), SceneError> {
    let bytes = read_bytes(file, "")?;
    let ext = file.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let bad = |m: String| SceneError::new(file, m);
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
    match ext.as_str() {
        "tga" => super::tga::decode(&bytes).map(|t| (t.width, t.height, t.texels)).map_err(bad),
        "pfm" => super::pfm::decode(&bytes)
            .map(|p| {
                let texels = p.texels.iter().map(|c| [encode(c[0]), encode(c[1]), encode(c[2]), 255]).collect();
                (p.width, p.height, texels)
            })
            .map_err(bad),
        "png" | "jpg" | "jpeg" | "exr" => {
            let decoded = super::catch_quietly(|| image::load_from_memory(&bytes))
                .map_err(|p| bad(format!("corrupt image (the decoder failed: {p})")))?
                .map_err(|e| bad(format!("cannot decode image: {e}")))?;
            if decoded.width() > 16384 || decoded.height() > 16384 {
                return Err(bad(format!("image {}x{} is too large", decoded.width(), decoded.height())));
            }
            if ext == "exr" {
                let f = decoded.to_rgba32f();
                let texels = f.pixels().map(|p| [encode(p[0]), encode(p[1]), encode(p[2]), 255]).collect();
                Ok((f.width(), f.height(), texels))
            } else {
                let r = decoded.to_rgba8();
                Ok((r.width(), r.height(), r.pixels().map(|p| p.0).collect()))
            }
        }
        _ => Err(bad(format!("unsupported texture format '.{ext}' (expected .tga, .png, .jpg, .exr or .pfm)"))),
    }
}
