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

/// Refractive indices at ~550 nm of the named glasses of pbrt-v4 (its `glass-*` spectra) and of Mitsuba 3's
/// `int_ior`/`ext_ior` names (the table in Mitsuba's dielectric documentation).
const NAMED_IORS: &[(&str, f32)] = &[
    ("glass-BK7", 1.5168),
    ("glass-BAF10", 1.670),
    ("glass-FK51A", 1.4866),
    ("glass-LASF9", 1.850),
    ("glass-F5", 1.6034),
    ("glass-F10", 1.6137),
    ("glass-F11", 1.621),
    ("vacuum", 1.0),
    ("helium", 1.00004),
    ("hydrogen", 1.00013),
    ("air", 1.00028),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Relative index (inside / outside) of a dielectric: pbrt's `eta` (a number, an RGB triple — its mean, as
/// mislab has no dispersion — or a named glass), or Mitsuba's `int_ior` / `ext_ior` (numbers or names).
fn dielectric_eta(desc: &MaterialDesc, warn: &mut impl FnMut(&str)) -> f32 {
    let mut value = |name: &str, default: f32| match desc.params.get(name) {
        Some(MatParam::Float(v)) if *v > 0.0 => *v,
        Some(MatParam::Rgb(c)) => {
            if c.max_element() - c.min_element() > 1e-4 {
                warn("a dielectric of one η (the mean of its RGB η; no dispersion)");
            }
            (c.x + c.y + c.z) / 3.0
        }
        Some(MatParam::Spectrum(s) | MatParam::Str(s)) => {
            match NAMED_IORS.iter().find(|(n, _)| n.eq_ignore_ascii_case(s)) {
                Some((_, v)) => *v,
                None => {
                    warn("a dielectric of η 1.5 (its named index is unknown)");
                    1.5
                }
            }
        }
        _ => default,
    };
    if desc.params.contains_key("int_ior") || desc.params.contains_key("ext_ior") {
        // Mitsuba's defaults: BK7 inside, air outside.
        return value("int_ior", 1.5046) / value("ext_ior", 1.000277);
    }
    value("eta", 1.5)
}

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
        "diffusetransmission" | "difftrans" => {
            // pbrt-v4: reflectance 0.25, transmittance 0.25, both × scale. Mitsuba 3's difftrans has
            // transmittance only (its reflection is 0).
            let mitsuba = desc.kind == "difftrans";
            let r_default = if mitsuba { Vec3::ZERO } else { Vec3::splat(0.25) };
            let (r, rt) = color(desc, &["reflectance"], r_default, scene, cache)?;
            let (tr, tt) =
                color(desc, &["transmittance"], Vec3::splat(if mitsuba { 0.5 } else { 0.25 }), scene, cache)?;
            // One texture slot (base_tex): a textured transmittance shares the reflectance's texture, as the living
            // room's leaves do; a different texture, or a textured transmittance alone, is approximated.
            let transmittance_textured = tt.is_some();
            if rt.is_some() && tt.is_some() && rt != tt {
                warn("diffuse transmission whose transmittance uses the reflectance's texture");
            }
            // With only the transmittance textured, the texture tints the (untextured) reflectance too.
            if rt.is_none() && tt.is_some() && r != Vec3::ZERO {
                warn("diffuse transmission whose reflectance takes the transmittance's texture too");
            }
            let texture = rt.or(tt);
            let kind = MaterialKind::DiffuseTransmission { reflectance: r, transmittance: tr, transmittance_textured };
            with_texture(Material { kind, ..Material::lambert(&desc.name, r) }, texture)
        }
        "dielectric" | "roughdielectric" | "thindielectric" => {
            let thin = desc.kind == "thindielectric";
            let eta = dielectric_eta(desc, &mut warn);
            // Smooth unless the file gives a roughness (pbrt's default roughness is 0; Mitsuba's roughdielectric
            // defaults to α = 0.1).
            let mut alpha = alpha_of(desc);
            let rough_default = desc.kind == "roughdielectric" && !desc.params.contains_key("alpha");
            if rough_default && alpha_uv(desc).is_none() {
                alpha = 0.1;
            }
            let (au, av) = alpha_uv(desc).unwrap_or((alpha, alpha));
            if thin && au.max(av) >= super::DELTA_ALPHA {
                warn("a smooth thin dielectric (its roughness is dropped)");
            }
            let (tr, _) = color(desc, &["specular_transmittance"], Vec3::ONE, scene, cache)?;
            let (re, _) = color(desc, &["specular_reflectance"], Vec3::ONE, scene, cache)?;
            if tr != re {
                warn("a dielectric with one tint (specular_transmittance) on both lobes");
            }
            if desc.params.values().any(|p| matches!(p, MatParam::Texture(_))) {
                warn("an untextured dielectric");
            }
            let (au, av) = if thin { (0.0, 0.0) } else { (au, av) };
            let kind = MaterialKind::Dielectric { eta, alpha_u: au, alpha_v: av, tint: tr, thin };
            Material { kind, base_color: tr, specular: 0.0, ..Default::default() }
        }
        "interface" | "null" => {
            warn("invisible: its shapes are left out (an interface between media, which mislab does not have)");
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

    #[test]
    fn dielectric_and_diffuse_transmission() {
        let mut s = Scene::default();
        let mut c = TextureCache::default();
        let mut w = vec![];
        let kind = |d: &MaterialDesc, s: &mut Scene, c: &mut TextureCache, w: &mut Vec<String>| match map(d, s, c, w)
            .unwrap()
        {
            Mapped::Material(m) => m.kind,
            Mapped::Invisible => panic!("{} left out", d.kind),
        };
        // pbrt: eta and a remapped roughness (√0.04 = 0.2); remaproughness false keeps it.
        let d = desc("dielectric", vec![("eta", MatParam::Float(1.33)), ("roughness", MatParam::Float(0.04))]);
        assert_eq!(
            kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { eta: 1.33, alpha_u: 0.2, alpha_v: 0.2, tint: Vec3::ONE, thin: false }
        );
        let d = desc(
            "dielectric",
            vec![
                ("uroughness", MatParam::Float(0.1)),
                ("vroughness", MatParam::Float(0.3)),
                ("remaproughness", MatParam::Bool(false)),
            ],
        );
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { eta, alpha_u, alpha_v, .. } if eta == 1.5 && alpha_u == 0.1 && alpha_v == 0.3));
        assert!(w.is_empty(), "{w:?}");
        // A named glass: its index at ~550 nm.
        let d = desc("dielectric", vec![("eta", MatParam::Spectrum("glass-BK7".into()))]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w), MaterialKind::Dielectric { eta, .. } if eta == 1.5168));
        // Mitsuba: int_ior / ext_ior by name or number; roughdielectric defaults to α = 0.1; thin is smooth.
        let d = desc("dielectric", vec![("int_ior", MatParam::Str("water".into())), ("ext_ior", MatParam::Float(1.0))]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w), MaterialKind::Dielectric { eta, .. } if eta == 1.333));
        let d = desc("roughdielectric", vec![]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { alpha_u, thin: false, .. } if alpha_u == 0.1));
        let d = desc("thindielectric", vec![]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { thin: true, alpha_u, .. } if alpha_u == 0.0));
        assert!(w.is_empty(), "{w:?}");
        // pbrt's diffusetransmission: reflectance and transmittance × scale.
        let d = desc(
            "diffusetransmission",
            vec![("transmittance", MatParam::Rgb(Vec3::new(0.2, 0.4, 0.6))), ("scale", MatParam::Float(0.5))],
        );
        assert_eq!(
            kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::DiffuseTransmission {
                reflectance: Vec3::splat(0.125),
                transmittance: Vec3::new(0.1, 0.2, 0.3),
                transmittance_textured: false
            }
        );
        // Interfaces between media stay left out.
        assert!(matches!(map(&desc("interface", vec![]), &mut s, &mut c, &mut w).unwrap(), Mapped::Invisible));
    }
}
