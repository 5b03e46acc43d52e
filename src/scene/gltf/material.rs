//! Materials and textures: glTF materials converted on first use (factors sanitised, extensions applied),
//! texture references with their samplers and `KHR_texture_transform`, and images decoded once and shared.

use super::container::fetch_uri;
use super::notes::Notes;
use super::{json, quoted, Loader, Res, MAX_TEXTURE_SIZE};
use crate::scene::{Material, Texture, TextureRef, Wrap};
use glam::Vec3;
use json::validation::Checked;
use std::io::Cursor;
use std::rc::Rc;

/// Texture cache key: image, wrap S, wrap T, nearest, sRGB.
pub(super) type TexKey = (usize, u8, u8, bool, bool);

/// A decoded RGBA8 image, shared by the textures that sample it.
pub(super) struct Decoded {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
}

impl Loader<'_> {
    /// The scene material index for a glTF material (None = the default material), converting on first use.
    pub(super) fn material(&mut self, index: Option<usize>) -> Res<u32> {
        if let Some(&id) = self.materials.get(&index) {
            return Ok(id);
        }
        let material = match index {
            None => Material::default(),
            Some(i) => self.convert_material(i)?,
        };
        let id = self.scene.materials.len() as u32;
        self.scene.materials.push(material);
        self.materials.insert(index, id);
        Ok(id)
    }

    fn convert_material(&mut self, index: usize) -> Res<Material> {
        let root = self.root;
        let count = root.materials.len();
        let m = root
            .materials
            .get(index)
            .ok_or_else(|| format!("material {index} does not exist (the file has {count} materials)"))?;
        let label = format!("material {index}{}", quoted(&m.name));
        let mut material = material_factors(m, &label, &mut self.notes);
        let pbr = &m.pbr_metallic_roughness;
        material.base_color_texture = self.texture_opt(&pbr.base_color_texture, true, &label)?;
        material.metallic_roughness_texture = self.texture_opt(&pbr.metallic_roughness_texture, false, &label)?;
        // glTF emission is factor × texture: with a zero factor the texture cannot contribute.
        if material.emission.max_element() > 0.0 {
            material.emissive_texture = self.texture_opt(&m.emissive_texture, true, &label)?;
        }
        let specular = m.extensions.as_ref().and_then(|e| e.specular.as_ref());
        if specular.is_some_and(|s| {
            s.specular_texture.is_some() || s.specular_color_texture.is_some() || s.specular_color_factor.0 != [1.0; 3]
        }) {
            self.notes.once("specular", || {
                format!("KHR_materials_specular colour and textures are ignored; only specularFactor is used ({label})")
            });
        }
        if m.alpha_mode != Checked::Valid(json::material::AlphaMode::Opaque) {
            self.notes.once("alpha", || {
                format!("alphaMode MASK/BLEND is ignored: surfaces are rendered opaque (first seen in {label})")
            });
        }
        Ok(material)
    }

    fn texture_opt(&mut self, info: &Option<json::texture::Info>, srgb: bool, label: &str) -> Res<Option<TextureRef>> {
        info.as_ref().map(|info| self.texture_ref(info, srgb, label)).transpose()
    }

    /// A texture reference with its sampler settings and `KHR_texture_transform`.
    fn texture_ref(&mut self, info: &json::texture::Info, srgb: bool, label: &str) -> Res<TextureRef> {
        let root = self.root;
        let ti = info.index.value();
        let count = root.textures.len();
        let texture = root
            .textures
            .get(ti)
            .ok_or_else(|| format!("{label}: texture {ti} does not exist (the file has {count} textures)"))?;
        let (wrap_s, wrap_t, nearest) = self.sampler(texture.sampler, label)?;
        // gltf-json fills a missing (required) "source" with u32::MAX, for the texture extensions that carry
        // their own source; we support none of those.
        let image = texture.source.value();
        if image == u32::MAX as usize {
            return Err(format!("{label}: texture {ti} has no source image (its \"source\" is missing)"));
        }
        let key = (image, wrap_s as u8, wrap_t as u8, nearest, srgb);
        let id = match self.textures.get(&key) {
            Some(&id) => id,
            None => {
                let decoded = self.image(image, label)?;
                let name = texture.name.clone().unwrap_or_else(|| image_name(root, image));
                let (width, height, texels) = (decoded.width, decoded.height, decoded.texels.clone());
                let id = self.scene.textures.len() as u32;
                let kind = crate::scene::TextureKind::Image;
                self.scene.textures.push(Texture { name, width, height, texels, srgb, wrap_s, wrap_t, nearest, kind });
                self.textures.insert(key, id);
                id
            }
        };
        let mut reference = TextureRef::identity(id);
        let mut texcoord = info.tex_coord;
        if let Some(t) = info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref()) {
            let transform = texture_transform(t.offset.0, t.rotation.0, t.scale.0);
            if transform.iter().flatten().all(|x| x.is_finite()) {
                reference.transform = transform;
            } else {
                // Non-finite UVs would turn every texel lookup into NaN; the untransformed texture is the repair.
                let (offset, rotation, scale) = (t.offset.0, t.rotation.0, t.scale.0);
                self.notes.push(format!(
                    "{label}: non-finite KHR_texture_transform ignored (offset {offset:?}, rotation {rotation}, scale {scale:?})"
                ));
            }
            texcoord = t.tex_coord.unwrap_or(texcoord);
        }
        if texcoord != 0 {
            self.notes.once("texcoord", || {
                format!("{label}: a texture uses TEXCOORD_{texcoord}; only TEXCOORD_0 is loaded and is used instead")
            });
        }
        Ok(reference)
    }

    fn sampler(&self, sampler: Option<json::Index<json::texture::Sampler>>, label: &str) -> Res<(Wrap, Wrap, bool)> {
        let Some(index) = sampler.map(|s| s.value()) else { return Ok((Wrap::Repeat, Wrap::Repeat, false)) };
        let count = self.root.samplers.len();
        let s = self
            .root
            .samplers
            .get(index)
            .ok_or_else(|| format!("{label}: sampler {index} does not exist (the file has {count} samplers)"))?;
        let nearest = s.mag_filter == Some(Checked::Valid(json::texture::MagFilter::Nearest));
        Ok((wrap(s.wrap_s), wrap(s.wrap_t), nearest))
    }

    /// Decodes image `index` once (textures with different samplers or colour spaces share it).
    fn image(&mut self, index: usize, label: &str) -> Res<Rc<Decoded>> {
        if let Some(image) = self.images.get(&index) {
            return Ok(image.clone());
        }
        let root = self.root;
        let count = root.images.len();
        let image = root
            .images
            .get(index)
            .ok_or_else(|| format!("{label}: image {index} does not exist (the file has {count} images)"))?;
        let what = format!("image {index} ({})", image_name(root, index));
        let bytes = match (&image.uri, image.buffer_view) {
            (Some(uri), _) => fetch_uri(self.uris(), uri, |p| {
                crate::io::input_file::read_bounded(p, crate::io::input_file::MAX_IMAGE_BYTES)
                    .map_err(|e| e.to_string())
            }),
            (None, Some(view)) => self.view(view.value()).map(|(bytes, _)| bytes.to_vec()),
            (None, None) => Err("has neither a uri nor a bufferView".into()),
        }
        .map_err(|m| format!("{what}: {m}"))?;
        let left = self.texel_limit.saturating_sub(self.texel_used);
        let decoded = Rc::new(decode_image(&bytes, left, self.texel_limit).map_err(|m| format!("{what}: {m}"))?);
        self.texel_used += 4 * decoded.texels.len() as u64;
        self.images.insert(index, decoded.clone());
        Ok(decoded)
    }
}

/// Material factors (no textures), sanitised: non-finite values fall back to the glTF defaults.
fn material_factors(m: &json::Material, label: &str, notes: &mut Notes) -> Material {
    let mut repaired = false;
    let mut clean = |x: f32, lo: f32, hi: f32, default: f32| {
        repaired |= !x.is_finite();
        if x.is_finite() {
            x.clamp(lo, hi)
        } else {
            default
        }
    };
    let pbr = &m.pbr_metallic_roughness;
    let [r, g, b, _alpha] = pbr.base_color_factor.0;
    let ext = m.extensions.as_ref();
    let strength = ext.and_then(|e| e.emissive_strength.as_ref()).map_or(1.0, |s| s.emissive_strength.0);
    let specular = ext.and_then(|e| e.specular.as_ref()).map_or(1.0, |s| s.specular_factor.0);
    let strength = clean(strength, 0.0, f32::MAX, 1.0);
    let emissive = m.emissive_factor.0.map(|e| clean(e, 0.0, f32::MAX, 0.0));
    let material = Material {
        name: m.name.clone().unwrap_or_else(|| label.to_string()),
        base_color: Vec3::new(clean(r, 0.0, 1.0, 1.0), clean(g, 0.0, 1.0, 1.0), clean(b, 0.0, 1.0, 1.0)),
        metallic: clean(pbr.metallic_factor.0, 0.0, 1.0, 1.0),
        roughness: clean(pbr.roughness_factor.0, 0.0, 1.0, 1.0),
        specular: clean(specular, 0.0, 1.0, 1.0),
        emission: Vec3::from(emissive) * strength,
        ..Material::default()
    };
    if repaired {
        notes.push(format!("{label}: non-finite factors replaced by the glTF defaults"));
    }
    material
}

fn wrap(mode: Checked<json::texture::WrappingMode>) -> Wrap {
    use json::texture::WrappingMode::*;
    match mode {
        Checked::Valid(ClampToEdge) => Wrap::Clamp,
        Checked::Valid(MirroredRepeat) => Wrap::Mirror,
        _ => Wrap::Repeat,
    }
}

/// `KHR_texture_transform` as the 2×3 matrix T·R·S of the extension. R maps (u, v) to
/// (u·cos + v·sin, −u·sin + v·cos): the sense the extension's worked example (offset [0, 1], rotation π/2,
/// scale 0.5 selects the lower-left quadrant) and the reference viewers use; its GLSL snippet, read as
/// column-major, would give the opposite sense.
fn texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 3]; 2] {
    let (s, c) = rotation.sin_cos();
    let [sx, sy] = scale;
    let [ox, oy] = offset;
    [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]]
}

fn image_name(root: &json::Root, index: usize) -> String {
    let image = &root.images[index];
    match (&image.name, &image.uri) {
        (Some(name), _) => name.clone(),
        (None, Some(uri)) if !uri.starts_with("data:") => uri.clone(),
        _ => format!("image {index}"),
    }
}

/// Decodes PNG/JPEG bytes to RGBA8, refusing images above the size limit, or whose texels would not fit in
/// what is left of the device's texel buffer (`budget` bytes), from their declared size before decoding them.
fn decode_image(bytes: &[u8], budget: u64, limit: u64) -> Res<Decoded> {
    let reader = || image::ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| e.to_string());
    let (width, height) = reader()?.into_dimensions().map_err(|e| format!("cannot decode the image: {e}"))?;
    if width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
        return Err(format!(
            "{width}×{height} texels exceeds the texture size limit of {MAX_TEXTURE_SIZE} texels per side"
        ));
    }
    let need = 4 * width as u64 * height as u64;
    if need > budget {
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        return Err(format!(
            "{width}×{height} texels need {:.1} MiB ({need} bytes) as RGBA8, more than the {:.1} MiB left for the scene's texels of the device's max_storage_buffer_binding_size of {} MiB ({limit} bytes); refused before decoding",
            mib(need),
            mib(budget),
            limit >> 20
        ));
    }
    let image = reader()?.decode().map_err(|e| format!("cannot decode the image: {e}"))?;
    let rgba = image.to_rgba8();
    let texels = rgba.as_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Ok(Decoded { width, height, texels })
}
