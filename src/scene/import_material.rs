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
    /// Where the scene names the file (`scene.pbrt: line 12`), for errors about it.
    pub referenced_by: String,
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
    /// pbrt's 2D `checkerboard` of two colours under a UV map (rows as [`TextureRef::transform`], in mislab's
    /// v-down convention).
    Checkerboard {
        /// The even checks.
        tex1: Vec3,
        /// The odd checks.
        tex2: Vec3,
        /// The UV map.
        uv: [[f32; 3]; 2],
    },
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
    /// Where the file declares it (`scene.pbrt: line 12`), named in the warnings; empty for a format's defaults.
    pub at: String,
}

impl MaterialDesc {
    /// "name (kind, scene.pbrt: line 12)" for messages.
    fn shown(&self) -> String {
        if self.at.is_empty() || self.name == self.at {
            format!("{} ({})", self.name, self.kind)
        } else {
            format!("{} ({}, {})", self.name, self.kind, self.at)
        }
    }
}

/// What a description becomes.
pub enum Mapped {
    /// Render with this material.
    Material(Box<Material>),
    /// Leave the shapes out (a see-through interface mislab cannot refract through yet).
    Invisible,
}

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
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
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
    let mut warn = |what: &str| warnings.push(format!("material {} approximated as {what}", desc.shown()));
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
            // Mitsuba's roughconductor is Beckmann unless it says ggx; pbrt-v4's conductor is always GGX.
            let beckmann = desc.kind == "roughconductor" && mitsuba_beckmann(desc, &mut warn);
            let with_distribution = |kind: MaterialKind| match kind {
                MaterialKind::Conductor { eta, k, alpha_u, alpha_v, tint, .. } => {
                    MaterialKind::Conductor { eta, k, alpha_u, alpha_v, tint, beckmann }
                }
                other => other,
            };
            match (conductor_eta_k(desc), t) {
                // RGB or named η and k: the complex-Fresnel conductor exactly (MaterialKind::Conductor).
                // Mitsuba's specular_reflectance scales the Fresnel term: the conductor's tint.
                (Some((eta, k)), None) if desc.params.get("reflectance").is_none() => Material {
                    kind: MaterialKind::Conductor { eta, k, alpha_u: au, alpha_v: av, tint: c, beckmann },
                    ..Material::conductor(&desc.name, conductor_f0(desc), alpha)
                },
                // A reflectance colour (pbrt-v4's "reflectance" form: η = 1, k from r) or a named spectrum (its
                // normal-incidence reflectance, named_spectra): the complex-Fresnel conductor of that F(0).
                (_, None) => {
                    let f0 = if desc.params.contains_key("reflectance") { c } else { conductor_f0(desc) * c };
                    if desc.params.get("reflectance").is_none() {
                        warn("a complex-Fresnel conductor of reflectance 0.9 (a spectrum not in the named-spectra table)");
                    }
                    Material {
                        kind: with_distribution(MaterialKind::conductor_from_reflectance(f0, au, av)),
                        ..Material::conductor(&desc.name, f0, alpha)
                    }
                }
                // A textured reflectance: the Fresnel-free GGX conductor, which reads the texture.
                (_, Some(t)) => {
                    warn("a Fresnel-free GGX conductor with its textured normal-incidence reflectance");
                    if beckmann {
                        warn("a Beckmann conductor rendered as GGX (its reflectance is textured)");
                    }
                    with_texture(Material::conductor(&desc.name, conductor_f0(desc) * c, alpha), Some(t))
                }
            }
        }
        "coateddiffuse" | "plastic" | "roughplastic" => return coated_diffuse(desc, scene, cache, warnings),
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
            let beckmann = desc.kind == "roughdielectric" && mitsuba_beckmann(desc, &mut warn);
            if thin && au.max(av) >= super::DELTA_ALPHA {
                warn("a smooth thin dielectric (its roughness is dropped)");
            }
            let (tr, _) = color(desc, &["specular_transmittance"], Vec3::ONE, scene, cache)?;
            let (re, _) = color(desc, &["specular_reflectance"], Vec3::ONE, scene, cache)?;
            if tr != re {
                warn("a dielectric with one tint (specular_transmittance) on both lobes");
            }
            if desc.params.values().any(|p| matches!(p, MatParam::Texture(_) | MatParam::Checkerboard { .. })) {
                warn("an untextured dielectric");
            }
            let (au, av) = if thin { (0.0, 0.0) } else { (au, av) };
            let kind = MaterialKind::Dielectric { eta, alpha_u: au, alpha_v: av, tint: tr, thin, beckmann };
            Material { name: desc.name.clone(), kind, base_color: tr, specular: 0.0, ..Default::default() }
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

/// pbrt-v4 `coateddiffuse` and Mitsuba `plastic` / `roughplastic` onto `MaterialKind::CoatedDiffuse` (the analytic
/// coat-over-Lambert model; docs/materials.md measures it against pbrt's stochastic layered evaluation).
fn coated_diffuse(
    desc: &MaterialDesc,
    scene: &mut Scene,
    cache: &mut TextureCache,
    warnings: &mut Vec<String>,
) -> Result<Mapped, SceneError> {
    let mut warn = |what: &str| warnings.push(format!("material {}: {what}", desc.shown()));
    let f = |n: &str| match desc.params.get(n) {
        Some(MatParam::Float(v)) => Some(*v),
        Some(MatParam::Rgb(c)) => Some(c.x),
        _ => None,
    };
    let pbrt = desc.kind == "coateddiffuse";
    let (mut c, t) = color(desc, &["reflectance", "diffuse_reflectance"], Vec3::splat(0.5), scene, cache)?;
    // Smooth (Mitsuba `plastic`, pbrt roughness 0) is α = 0, which the GPU clamps to ALPHA_MIN.
    let alpha = if desc.kind == "plastic" { 0.0 } else { alpha_of(desc) };
    let alpha = if desc.kind == "roughplastic" && !desc.params.contains_key("alpha") && alpha_uv(desc).is_none() {
        0.1 // Mitsuba's default
    } else {
        alpha
    };
    let (au, av) = if desc.kind == "plastic" { (0.0, 0.0) } else { alpha_uv(desc).unwrap_or((alpha, alpha)) };
    let eta = if pbrt {
        match desc.params.get("eta") {
            None => 1.5,
            Some(MatParam::Float(e)) => *e,
            Some(MatParam::Rgb(e)) => e.x,
            Some(other) => {
                warn(&format!("eta {other:?} is not a number; the coat uses η = 1.5"));
                1.5
            }
        }
    } else {
        mitsuba_ior(desc, "int_ior", 1.49, &mut warn) / mitsuba_ior(desc, "ext_ior", 1.000277, &mut warn)
    };
    let eta = if eta > 1.0 && eta.is_finite() {
        eta
    } else {
        warn(&format!("a coat of relative η = {eta} (the model needs η > 1) rendered with η = 1.5"));
        1.5
    };
    if pbrt {
        // pbrt's medium between coat and base: the analytic model has none (thickness 0.01 with albedo 0 only
        // absorbs exp(−0.01/cosθ) per crossing in pbrt; the table in docs/materials.md includes it).
        let medium = f("albedo").is_some_and(|a| a != 0.0)
            || desc.params.get("albedo").is_some_and(|a| !matches!(a, MatParam::Float(_) | MatParam::Rgb(_)))
            || f("g").is_some_and(|g| g != 0.0)
            || f("thickness").is_some_and(|d| (d - 0.01).abs() > 1e-6);
        if medium {
            warn("its layer medium (thickness/albedo/g) is ignored: the analytic coat has no medium");
        }
    }
    // Mitsuba's roughplastic is Beckmann unless it says ggx; pbrt-v4's coat is always GGX; `plastic` is smooth.
    let beckmann = desc.kind == "roughplastic" && mitsuba_beckmann(desc, &mut warn);
    let nonlinear = matches!(desc.params.get("nonlinear"), Some(MatParam::Bool(true)));
    if desc.kind == "roughplastic" {
        // Mitsuba's diffuse term is r/(1 − F̄ᵢ) (linear) or r/(1 − r·F̄ᵢ) (nonlinear) with ITS internal reflectance,
        // estimated over the rough interface (smaller than the smooth one this model uses: 0.524 against 0.590
        // for Beckmann α 0.3): the base is chosen so that this model's R'/(1 − R'·F̄ᵢ) equals that term.
        let fi = super::coated::coated_internal_reflectance(eta);
        let fi_m = super::coated::mitsuba_rough_internal_reflectance(eta, au, beckmann);
        let conv = |r: f32| {
            let r = r.clamp(0.0, 1.0);
            let target = if nonlinear { r / (1.0 - r * fi_m) } else { r / (1.0 - fi_m) };
            super::coated::reflectance_for_diffuse_term(target, fi)
        };
        c = Vec3::new(conv(c.x), conv(c.y), conv(c.z));
        if t.is_some() {
            warn("Mitsuba's diffuse reflectance of a texture converted at the texture factor");
        }
    }
    if !pbrt {
        if desc.kind == "plastic" && !nonlinear {
            // Mitsuba's default linear form: its reflectance is the base's share; converted exactly for colours.
            let fi = super::coated::coated_internal_reflectance(eta);
            let lin = |r: f32| super::coated::reflectance_from_linear(r, fi);
            c = Vec3::new(lin(c.x), lin(c.y), lin(c.z));
            if t.is_some() {
                warn("Mitsuba's linear (nonlinear = false) reflectance of a texture converted at the texture factor");
            }
        }
        if f("specular_reflectance").is_some_and(|s| s != 1.0) {
            warn("specular_reflectance other than 1 is ignored");
        }
    }
    let m = Material {
        kind: MaterialKind::CoatedDiffuse { eta, alpha_u: au, alpha_v: av, beckmann },
        ..Material::coated_diffuse(&desc.name, c, eta, au)
    };
    Ok(Mapped::Material(Box::new(with_texture(m, t))))
}

/// Whether a Mitsuba rough BSDF's `distribution` is Beckmann (its default) rather than `ggx`; any other name
/// (`phong`) is rendered as Beckmann with a warning.
fn mitsuba_beckmann(desc: &MaterialDesc, warn: &mut impl FnMut(&str)) -> bool {
    match desc.params.get("distribution") {
        Some(MatParam::Str(d)) if d == "ggx" => false,
        None => true,
        Some(MatParam::Str(d)) if d == "beckmann" => true,
        Some(other) => {
            warn(&format!("Beckmann (its distribution {other:?} is not ggx or beckmann)"));
            true
        }
    }
}

/// A Mitsuba index of refraction: a number, or one of the names of `NAMED_IORS` (Mitsuba's IOR table).
fn mitsuba_ior(desc: &MaterialDesc, name: &str, default: f32, warn: &mut impl FnMut(&str)) -> f32 {
    match desc.params.get(name) {
        None => default,
        Some(MatParam::Float(v)) => *v,
        Some(MatParam::Str(s)) => {
            NAMED_IORS.iter().find(|(n, _)| n.eq_ignore_ascii_case(s)).map(|(_, v)| *v).unwrap_or_else(|| {
                warn(&format!("unknown {name} \"{s}\"; {default} used"));
                default
            })
        }
        Some(other) => {
            warn(&format!("{name} {other:?} is not a number; {default} used"));
            default
        }
    }
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
                let index = cache.load(&t.file, t.srgb, &t.referenced_by, scene)?;
                let r = TextureRef { texture: index, transform: t.uv, texcoord: 0 };
                return Ok((t.scale * scale, Some(r)));
            }
            Some(MatParam::Checkerboard { tex1, tex2, uv }) => {
                let index = cache.checkerboard(*tex1, *tex2, scene);
                return Ok((Vec3::splat(scale), Some(TextureRef { texture: index, transform: *uv, texcoord: 0 })));
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

/// RGB η and k of a conductor: RGB values, pbrt's named spectra (`metal-Au-eta`; super::named_spectra), Mitsuba's
/// `material` name, or pbrt's default (copper) when neither is given. None when a name is not in the table.
fn conductor_eta_k(desc: &MaterialDesc) -> Option<(Vec3, Vec3)> {
    use super::named_spectra::{lookup, Part};
    let get = |name: &str, part: Part| match desc.params.get(name) {
        Some(MatParam::Rgb(c)) => Some(*c),
        Some(MatParam::Float(f)) => Some(Vec3::splat(*f)),
        Some(MatParam::Spectrum(s)) => lookup(s, part),
        None => None,
        _ => None,
    };
    if let Some(MatParam::Str(m)) = desc.params.get("material") {
        if desc.params.get("eta").is_none() && desc.params.get("k").is_none() {
            return Some((lookup(&format!("metal-{m}-eta"), Part::Eta)?, lookup(&format!("metal-{m}-k"), Part::K)?));
        }
    }
    let absent = |n: &str| !desc.params.contains_key(n);
    let eta = if absent("eta") { lookup("metal-Cu-eta", Part::Eta) } else { get("eta", Part::Eta) }?;
    let k = if absent("k") { lookup("metal-Cu-k", Part::K) } else { get("k", Part::K) }?;
    Some((eta, k))
}

/// Normal-incidence Fresnel reflectance of the conductor's η / k (copper's if absent); 0.9 for names not in the
/// table.
fn conductor_f0(desc: &MaterialDesc) -> Vec3 {
    conductor_eta_k(desc).map_or(Vec3::splat(0.9), |(eta, k)| super::named_spectra::f0(eta, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc(kind: &str, params: Vec<(&str, MatParam)>) -> MaterialDesc {
        MaterialDesc {
            name: "m".into(),
            kind: kind.into(),
            params: params.into_iter().map(|(n, p)| (n.to_string(), p)).collect(),
            at: String::new(),
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
            MaterialKind::Conductor { eta, k, alpha_u, alpha_v, .. } => {
                assert_eq!((eta, k), (Vec3::splat(1.5), Vec3::ZERO));
                assert!((alpha_u - 0.2).abs() < 1e-5 && (alpha_v - 0.2).abs() < 1e-5);
            }
            other => panic!("conductor mapped to {other:?}"),
        }
        assert!(w.is_empty(), "{w:?}");
        // A named metal: its RGB η and k from the named-spectra table, exactly, without a warning.
        let d = desc(
            "conductor",
            vec![("eta", MatParam::Spectrum("metal-Au-eta".into())), ("k", MatParam::Spectrum("metal-Au-k".into()))],
        );
        let Mapped::Material(m) = map(&d, &mut s, &mut c, &mut w).unwrap() else { panic!() };
        let au = |p| crate::scene::named_spectra::lookup(p, crate::scene::named_spectra::Part::Eta);
        assert!(matches!(m.kind, MaterialKind::Conductor { eta, .. } if Some(eta) == au("metal-Au-eta")));
        assert!(w.is_empty(), "{w:?}");
        // pbrt's default conductor is copper; an unknown spectrum name is approximated with a warning.
        let Mapped::Material(m) = map(&desc("conductor", vec![]), &mut s, &mut c, &mut w).unwrap() else { panic!() };
        assert!(matches!(m.kind, MaterialKind::Conductor { k, .. } if k.x > 3.0 && k.z < 2.5), "{:?}", m.kind);
        let d = desc("conductor", vec![("eta", MatParam::Spectrum("metal-Xx-eta".into()))]);
        let Mapped::Material(_) = map(&d, &mut s, &mut c, &mut w).unwrap() else { panic!() };
        assert_eq!(w.len(), 1, "{w:?}");
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
            MaterialKind::Dielectric {
                eta: 1.33,
                alpha_u: 0.2,
                alpha_v: 0.2,
                tint: Vec3::ONE,
                thin: false,
                beckmann: false
            }
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
        let d = desc("roughdielectric", vec![("distribution", MatParam::Str("ggx".into()))]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { alpha_u, thin: false, beckmann: false, .. } if alpha_u == 0.1));
        // Mitsuba's default distribution is Beckmann, rendered as such (no warning).
        let d = desc("roughdielectric", vec![("alpha", MatParam::Float(0.3))]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w),
            MaterialKind::Dielectric { alpha_u, beckmann: true, .. } if alpha_u == 0.3));
        let d = desc("roughdielectric", vec![("distribution", MatParam::Str("beckmann".into()))]);
        assert!(matches!(kind(&d, &mut s, &mut c, &mut w), MaterialKind::Dielectric { beckmann: true, .. }));
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
