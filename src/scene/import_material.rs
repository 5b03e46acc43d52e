//! Imported materials (pbrt-v4 and Mitsuba 3) onto mislab's [`Material`]: the parsers hand over a complete
//! description (kind name and every typed parameter, textures resolved to files), and this one file decides what
//! mislab renders for it. Kinds mislab has no BSDF for yet get the closest existing approximation and a warning
//! saying so; retarget this file when new material kinds land.

use super::import_texture::TextureCache;
use super::{Material, MaterialKind, Scene, SceneError, TextureRef};
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// An image texture as a material parameter: the file, its UV map (already in mislab's v-down convention) and
/// a constant factor it is multiplied by (pbrt `scale` textures, `scale` parameters).
#[derive(Clone, Debug, PartialEq)]
pub struct TexDesc {
    /// The image file.
    pub file: PathBuf,
    /// Rows of the affine UV map, as [`TextureRef::transform`].
    pub uv: [[f32; 3]; 2],
    /// Factor on the texel values.
    pub scale: Vec3,
    /// Whether 8-bit texels are sRGB-encoded (pbrt's default for 8-bit images; Mitsuba's `raw` = false).
    pub srgb: bool,
}

/// One typed material parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum MatParam {
    /// A number.
    Float(f32),
    /// An RGB triple.
    Rgb(Vec3),
    /// An image texture.
    Texture(TexDesc),
    /// A named spectrum (pbrt `"spectrum eta" "metal-Ag-eta"`).
    Spectrum(String),
    /// A string (distribution names and the like).
    Str(String),
    /// A flag.
    Bool(bool),
}

/// A material as the scene file describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// Name in the file (or `file:line` for anonymous ones).
    pub name: String,
    /// Kind: pbrt `diffuse`, `conductor`, ..., Mitsuba `diffuse`, `roughplastic`, ...
    pub kind: String,
    /// Every parameter, by name.
    pub params: BTreeMap<String, MatParam>,
}

/// What a description becomes.
pub enum Mapped {
    /// Render with this material.
    Material(Box<Material>),
    /// Leave the shapes out (a see-through interface mislab cannot refract through yet).
    Invisible,
}

/// Normal-incidence reflectance of common conductors, linear Rec.709 (the usual published F0 table values),
/// for pbrt's named `metal-*-eta` / `metal-*-k` spectra.
const NAMED_METALS: &[(&str, [f32; 3])] = &[
    ("Ag", [0.972, 0.960, 0.915]),
    ("Al", [0.913, 0.922, 0.924]),
    ("Au", [1.000, 0.766, 0.336]),
    ("Cu", [0.955, 0.638, 0.538]),
    ("CuZn", [0.910, 0.778, 0.423]),
];

/// Maps `desc` onto a mislab material, loading its textures into `scene` (through `cache`). Approximations add
/// one warning each to `warnings`.
pub fn map(
    desc: &MaterialDesc,
    scene: &mut Scene,
    cache: &mut TextureCache,
    warnings: &mut Vec<String>,
) -> Result<Mapped, SceneError> {
    let mut warn = |what: &str| warnings.push(format!("material {} ({}) approximated as {what}", desc.name, desc.kind));
    let m = match desc.kind.as_str() {
        "diffuse" => {
            let (c, t) = color(desc, &["reflectance"], Vec3::splat(0.5), scene, cache)?;
            with_texture(Material::lambert(&desc.name, c), t)
        }
        "conductor" | "roughconductor" | "coatedconductor" => {
            let alpha = alpha_of(desc);
            let (au, av) = alpha_uv(desc).unwrap_or((alpha, alpha));
            if desc.kind == "coatedconductor" {
                warn("a conductor without its coat");
            }
            let (c, t) = color(desc, &["reflectance", "specular_reflectance"], Vec3::ONE, scene, cache)?;
            match (desc.params.get("eta"), desc.params.get("k"), t) {
                // RGB η and k: the complex-Fresnel conductor exactly (MaterialKind::Conductor).
                (Some(MatParam::Rgb(eta)), Some(MatParam::Rgb(k)), None)
                    if desc.params.get("reflectance").is_none() =>
                {
                    // Mitsuba's specular_reflectance scales the Fresnel term; the conductor kind has no tint yet.
                    if c != Vec3::ONE {
                        warn("a complex-Fresnel conductor without its specular_reflectance tint (rendered as 1)");
                    }
                    Material {
                        kind: MaterialKind::Conductor { eta: *eta, k: *k, alpha_u: au, alpha_v: av },
                        ..Material::conductor(&desc.name, conductor_f0(desc), alpha)
                    }
                }
                // A reflectance colour (pbrt-v4's "reflectance" form: η = 1, k from r) or a named spectrum (its
                // normal-incidence reflectance, NAMED_METALS): the complex-Fresnel conductor of that F(0).
                (_, _, None) => {
                    let f0 = if desc.params.contains_key("reflectance") { c } else { conductor_f0(desc) * c };
                    if desc.params.contains_key("eta") && desc.params.get("reflectance").is_none() {
                        warn("a complex-Fresnel conductor with the named metal's normal-incidence reflectance");
                    }
                    Material {
                        kind: MaterialKind::conductor_from_reflectance(f0, au, av),
                        ..Material::conductor(&desc.name, f0, alpha)
                    }
                }
                // A textured reflectance: the Fresnel-free GGX conductor, which reads the texture.
                (_, _, Some(t)) => {
                    warn("a Fresnel-free GGX conductor with its textured normal-incidence reflectance");
                    with_texture(Material::conductor(&desc.name, conductor_f0(desc) * c, alpha), Some(t))
                }
            }
        }
        "coateddiffuse" | "plastic" | "roughplastic" => {
            let (c, t) = color(desc, &["reflectance", "diffuse_reflectance"], Vec3::splat(0.5), scene, cache)?;
            warn("a glTF dielectric (GGX specular with F0 0.04 over Lambert)");
            let alpha = alpha_of(desc).max(super::ALPHA_MIN);
            let mat = Material { specular: 1.0, roughness: alpha.sqrt(), ..Material::lambert(&desc.name, c) };
            with_texture(mat, t)
        }
        "diffusetransmission" => {
            let (c, t) = color(desc, &["reflectance"], Vec3::splat(0.25), scene, cache)?;
            warn("Lambert reflection only (its transmission is dropped)");
            with_texture(Material::lambert(&desc.name, c), t)
        }
        "dielectric" | "thindielectric" | "roughdielectric" | "interface" | "null" => {
            warn("invisible: its shapes are left out (no refraction yet; right for thin panes, not for solid glass)");
            return Ok(Mapped::Invisible);
        }
        _ => {
            let c = match desc.params.get("reflectance") {
                Some(MatParam::Rgb(c)) => *c,
                _ => Vec3::splat(0.5),
            };
            warn("Lambert (mislab has no such material)");
            Material::lambert(&desc.name, c)
        }
    };
    Ok(Mapped::Material(Box::new(m)))
}

fn with_texture(mut m: Material, t: Option<TextureRef>) -> Material {
    m.base_color_texture = t;
    m
}

/// A colour parameter (the first of `names` present): RGB, a float (grey), or a texture (its factor, and the
/// reference to it).
fn color(
    desc: &MaterialDesc,
    names: &[&str],
    default: Vec3,
    scene: &mut Scene,
    cache: &mut TextureCache,
) -> Result<(Vec3, Option<TextureRef>), SceneError> {
    let scale = match desc.params.get("scale") {
        Some(MatParam::Float(s)) if desc.kind == "diffusetransmission" => *s,
        _ => 1.0,
    };
    for n in names {
        match desc.params.get(*n) {
            Some(MatParam::Rgb(c)) => return Ok((*c * scale, None)),
            Some(MatParam::Float(f)) => return Ok((Vec3::splat(*f * scale), None)),
            Some(MatParam::Texture(t)) => {
                let index = cache.load(&t.file, t.srgb, scene)?;
                let r = TextureRef { texture: index, transform: t.uv, texcoord: 0 };
                return Ok((t.scale * scale, Some(r)));
            }
            _ => {}
        }
    }
    Ok((default * scale, None))
}

/// GGX α from pbrt's `roughness` / `uroughness` / `vroughness` (remapped by √ unless `remaproughness` is false;
/// anisotropy averaged) or Mitsuba's `alpha` / `alpha_u` / `alpha_v`.
fn alpha_of(desc: &MaterialDesc) -> f32 {
    let f = |n: &str| match desc.params.get(n) {
        Some(MatParam::Float(v)) => Some(*v),
        _ => None,
    };
    let mitsuba = f("alpha").or_else(|| Some((f("alpha_u")? + f("alpha_v")?) / 2.0));
    if let Some(a) = mitsuba {
        return a.max(0.0);
    }
    let r = f("roughness").or_else(|| Some((f("uroughness")? + f("vroughness")?) / 2.0)).unwrap_or(0.0).max(0.0);
    let remap = !matches!(desc.params.get("remaproughness"), Some(MatParam::Bool(false)));
    if remap {
        r.sqrt()
    } else {
        r
    }
}

/// Separate GGX α along u and v (pbrt `uroughness`/`vroughness`, Mitsuba `alpha_u`/`alpha_v`), remapped as
/// `alpha_of` does; None when the material gives one roughness.
fn alpha_uv(desc: &MaterialDesc) -> Option<(f32, f32)> {
    let f = |n: &str| match desc.params.get(n) {
        Some(MatParam::Float(v)) => Some(v.max(0.0)),
        _ => None,
    };
    if let (Some(u), Some(v)) = (f("alpha_u"), f("alpha_v")) {
        return Some((u, v));
    }
    let (u, v) = (f("uroughness")?, f("vroughness")?);
    let remap = !matches!(desc.params.get("remaproughness"), Some(MatParam::Bool(false)));
    Some(if remap { (u.sqrt(), v.sqrt()) } else { (u, v) })
}

/// Normal-incidence Fresnel reflectance from `eta` / `k` (RGB or a named metal); Cu, pbrt's default, if absent.
fn conductor_f0(desc: &MaterialDesc) -> Vec3 {
    let named = |s: &str| {
        let metal = s.trim_start_matches("metal-").split('-').next().unwrap_or("");
        NAMED_METALS.iter().find(|(n, _)| *n == metal).map(|(_, c)| Vec3::from_array(*c))
    };
    match (desc.params.get("eta"), desc.params.get("k")) {
        (Some(MatParam::Rgb(eta)), Some(MatParam::Rgb(k))) => {
            let f = |n: f32, k: f32| ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            Vec3::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
        }
        (Some(MatParam::Spectrum(s)), _) => named(s).unwrap_or(Vec3::splat(0.9)),
        (None, None) if desc.params.contains_key("material") => Vec3::splat(0.9),
        (None, None) => Vec3::from_array(NAMED_METALS[3].1),
        _ => Vec3::splat(0.9),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc(kind: &str, params: Vec<(&str, MatParam)>) -> MaterialDesc {
        MaterialDesc {
            name: "m".into(),
            kind: kind.into(),
            params: params.into_iter().map(|(n, p)| (n.to_string(), p)).collect(),
        }
    }

    #[test]
    fn diffuse_and_conductor() {
        let mut s = Scene::default();
        let mut c = TextureCache::default();
        let mut w = vec![];
        let d = desc("diffuse", vec![("reflectance", MatParam::Rgb(Vec3::new(0.1, 0.2, 0.3)))]);
        let Mapped::Material(m) = map(&d, &mut s, &mut c, &mut w).unwrap() else { panic!() };
        assert_eq!((m.base_color, m.metallic, m.roughness, m.specular), (Vec3::new(0.1, 0.2, 0.3), 0.0, 1.0, 0.0));
        assert!(w.is_empty());
        // eta 1.5, k 0: F0 = 0.04; roughness 0.04 remapped to α 0.2.
        let d = desc(
            "conductor",
            vec![
                ("eta", MatParam::Rgb(Vec3::splat(1.5))),
                ("k", MatParam::Rgb(Vec3::ZERO)),
                ("roughness", MatParam::Float(0.04)),
            ],
        );
        let Mapped::Material(m) = map(&d, &mut s, &mut c, &mut w).unwrap() else { panic!() };
        assert!((m.base_color.x - 0.04).abs() < 1e-6 && m.metallic == 1.0);
        assert!((m.alpha() - 0.2).abs() < 1e-5, "{}", m.alpha());
        // RGB η and k map to the complex-Fresnel conductor exactly, with no warning.
        match m.kind {
            MaterialKind::Conductor { eta, k, alpha_u, alpha_v } => {
                assert_eq!((eta, k), (Vec3::splat(1.5), Vec3::ZERO));
                assert!((alpha_u - 0.2).abs() < 1e-5 && (alpha_v - 0.2).abs() < 1e-5);
            }
            other => panic!("conductor mapped to {other:?}"),
        }
        assert!(w.is_empty(), "{w:?}");
        // A named metal: its normal-incidence reflectance as a complex-Fresnel conductor, with a warning.
        let d = desc("conductor", vec![("eta", MatParam::Spectrum("metal-Au-eta".into()))]);
        let Mapped::Material(m) = map(&d, &mut s, &mut c, &mut w).unwrap() else { panic!() };
        assert!(matches!(m.kind, MaterialKind::Conductor { .. }));
        assert_eq!(w.len(), 1);
    }
}
