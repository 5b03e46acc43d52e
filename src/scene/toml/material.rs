//! The `[materials]` table of a TOML scene: one `MaterialDef` per entry, checked per type (a key the type does not
//! take is an error that says so) and turned into a scene `Material`.

use super::*;

/// All material keys; which ones a type accepts is checked after parsing so the error can say why.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MaterialDef {
    #[serde(rename = "type")]
    kind: String,
    reflectance: Option<Splat<3>>,
    alpha: Option<f32>,
    base_color: Option<Splat<3>>,
    metallic: Option<f32>,
    roughness: Option<f32>,
    specular: Option<f32>,
    emission: Option<Splat<3>>,
    eta: Option<Splat<3>>,
    k: Option<Splat<3>>,
    alpha_u: Option<f32>,
    alpha_v: Option<f32>,
    tint: Option<Splat<3>>,
    transmittance: Option<Splat<3>>,
    thin: Option<bool>,
    distribution: Option<String>,
}

pub(super) fn material(
    ctx: &Ctx,
    name: &str,
    def: &Spanned<MaterialDef>,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let e = |m: &str| ctx.err(def, format!("material '{name}': {m}"));
    let d = def.get_ref();
    // Which keys each type takes; anything else given is an error rather than silently ignored.
    let given = [
        ("reflectance", d.reflectance.is_some()),
        ("alpha", d.alpha.is_some()),
        ("base_color", d.base_color.is_some()),
        ("metallic", d.metallic.is_some()),
        ("roughness", d.roughness.is_some()),
        ("specular", d.specular.is_some()),
        ("emission", d.emission.is_some()),
        ("eta", d.eta.is_some()),
        ("k", d.k.is_some()),
        ("alpha_u", d.alpha_u.is_some()),
        ("alpha_v", d.alpha_v.is_some()),
        ("tint", d.tint.is_some()),
        ("transmittance", d.transmittance.is_some()),
        ("thin", d.thin.is_some()),
        ("distribution", d.distribution.is_some()),
    ];
    let allowed: &[&str] = match d.kind.as_str() {
        "lambert" => &["reflectance", "emission"],
        "conductor" => &["reflectance", "alpha", "emission", "eta", "k", "alpha_u", "alpha_v", "tint", "distribution"],
        "metallic-roughness" => &["base_color", "metallic", "roughness", "specular", "emission"],
        "coated-diffuse" => &["reflectance", "eta", "alpha", "alpha_u", "alpha_v", "emission", "distribution"],
        "emitter" => &["emission"],
        "dielectric" => &["eta", "alpha", "alpha_u", "alpha_v", "tint", "thin", "emission", "distribution"],
        "diffuse-transmission" => &["reflectance", "transmittance", "emission"],
        other => {
            return Err(e(&format!(
                "unknown type \"{other}\" (expected lambert, conductor, metallic-roughness, coated-diffuse, \
                 dielectric, diffuse-transmission or emitter)"
            )))
        }
    };
    if let Some((key, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
        return Err(e(&format!("type \"{}\" does not take '{key}' (it takes: {})", d.kind, allowed.join(", "))));
    }
    let color = |key: &str, v: Option<Splat<3>>, default: f32| -> Result<Vec3, SceneError> {
        let c = Vec3::from(v.map(|s| s.0).unwrap_or([default; 3]));
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(e(&format!("{key} must be finite and non-negative")));
        }
        Ok(c)
    };
    let unit = |key: &str, v: Option<f32>, default: f32| -> Result<f32, SceneError> {
        let x = v.unwrap_or(default);
        if !(0.0..=1.0).contains(&x) {
            return Err(e(&format!("{key} must be in [0, 1] (got {x})")));
        }
        Ok(x)
    };
    let emission = color("emission", d.emission, 0.0)?;
    // The microfacet distribution of conductors, dielectrics and coats: "ggx" (the default) or "beckmann".
    let beckmann = match d.distribution.as_deref() {
        None | Some("ggx") => false,
        Some("beckmann") => true,
        Some(other) => return Err(e(&format!("unknown distribution \"{other}\" (expected \"ggx\" or \"beckmann\")"))),
    };
    let mut m = match d.kind.as_str() {
        "lambert" => Material::lambert(name, color("reflectance", d.reflectance, 0.8)?),
        "conductor" if d.eta.is_some() || d.k.is_some() => {
            // The complex-Fresnel conductor (MaterialKind::Conductor): α given once (isotropic) or per axis.
            if d.reflectance.is_some() {
                return Err(e("type \"conductor\" takes either 'reflectance' or 'eta'/'k', not both"));
            }
            let a = match (d.alpha, d.alpha_u, d.alpha_v) {
                (Some(a), None, None) => (a, a),
                (None, Some(u), Some(v)) => (u, v),
                _ => return Err(e("a conductor with 'eta'/'k' needs 'alpha', or both 'alpha_u' and 'alpha_v'")),
            };
            let (alpha_u, alpha_v) = (unit("alpha_u", Some(a.0), 0.0)?, unit("alpha_v", Some(a.1), 0.0)?);
            let (eta, k) = (color("eta", d.eta, 1.0)?, color("k", d.k, 0.0)?);
            if eta.min_element() <= 0.0 {
                return Err(e("eta must be positive"));
            }
            Material {
                name: name.into(),
                kind: MaterialKind::Conductor { eta, k, alpha_u, alpha_v, tint: color("tint", d.tint, 1.0)?, beckmann },
                base_color: Vec3::ONE,
                ..Default::default()
            }
        }
        "conductor" if beckmann => {
            return Err(e("'distribution' needs 'eta' and 'k' (the Fresnel-1 conductor is GGX only)"));
        }
        "conductor" if d.alpha_u.is_some() || d.alpha_v.is_some() => {
            return Err(e("'alpha_u'/'alpha_v' need 'eta' and 'k' (the Fresnel-1 conductor is isotropic: 'alpha')"));
        }
        "conductor" => {
            let alpha = unit(
                "alpha",
                Some(d.alpha.ok_or_else(|| e("type \"conductor\" needs 'alpha' (GGX α = roughness²)"))?),
                0.0,
            )?;
            Material::conductor(name, color("reflectance", d.reflectance, 1.0)?, alpha)
        }
        "coated-diffuse" => {
            // MaterialKind::CoatedDiffuse: η one number (the coat is not dispersive), α once or per axis.
            let eta = Vec3::from(d.eta.map(|s| s.0).unwrap_or([1.5; 3]));
            if eta.x != eta.y || eta.x != eta.z || !(eta.x > 1.0 && eta.x.is_finite()) {
                return Err(e("a coated-diffuse 'eta' must be one finite number > 1"));
            }
            let a = match (d.alpha, d.alpha_u, d.alpha_v) {
                (Some(a), None, None) => (a, a),
                (None, Some(u), Some(v)) => (u, v),
                _ => return Err(e("type \"coated-diffuse\" needs 'alpha', or both 'alpha_u' and 'alpha_v'")),
            };
            let (alpha_u, alpha_v) = (unit("alpha_u", Some(a.0), 0.0)?, unit("alpha_v", Some(a.1), 0.0)?);
            let reflectance = color("reflectance", d.reflectance, 0.5)?;
            Material {
                kind: MaterialKind::CoatedDiffuse { eta: eta.x, alpha_u, alpha_v, beckmann },
                ..Material::coated_diffuse(name, reflectance, eta.x, alpha_u)
            }
        }
        "dielectric" => {
            // Smooth (α = 0, delta lobes) unless α is given, once or per axis.
            let a = match (d.alpha, d.alpha_u, d.alpha_v) {
                (a, None, None) => (a.unwrap_or(0.0), a.unwrap_or(0.0)),
                (None, Some(u), Some(v)) => (u, v),
                _ => return Err(e("a dielectric takes 'alpha', or both 'alpha_u' and 'alpha_v'")),
            };
            let (alpha_u, alpha_v) = (unit("alpha_u", Some(a.0), 0.0)?, unit("alpha_v", Some(a.1), 0.0)?);
            let eta = color("eta", d.eta, 1.5)?;
            if eta.min_element() <= 0.0 || eta.max_element() != eta.min_element() {
                return Err(e("a dielectric's eta must be one positive number (relative index inside/outside)"));
            }
            let thin = d.thin.unwrap_or(false);
            if thin && (alpha_u.max(alpha_v) > 0.0 || beckmann) {
                return Err(e("a thin dielectric is smooth: it takes no 'alpha' or 'distribution'"));
            }
            let tint = color("tint", d.tint, 1.0)?;
            let kind = MaterialKind::Dielectric { eta: eta.x, alpha_u, alpha_v, tint, thin, beckmann };
            Material { name: name.into(), kind, base_color: tint, specular: 0.0, ..Default::default() }
        }
        "diffuse-transmission" => {
            let reflectance = color("reflectance", d.reflectance, 0.25)?;
            let transmittance = color("transmittance", d.transmittance, 0.25)?;
            let kind = MaterialKind::DiffuseTransmission { reflectance, transmittance, transmittance_textured: false };
            Material { kind, ..Material::lambert(name, reflectance) }
        }
        "metallic-roughness" => Material {
            name: name.into(),
            // glTF's defaults, so that this type means exactly what a glTF material with the same factors means.
            base_color: color("base_color", d.base_color, 1.0)?,
            metallic: unit("metallic", d.metallic, 1.0)?,
            roughness: unit("roughness", d.roughness, 1.0)?,
            specular: unit("specular", d.specular, 1.0)?,
            ..Default::default()
        },
        _ => {
            if d.emission.is_none() {
                return Err(e("type \"emitter\" needs 'emission' (radiance, linear RGB)"));
            }
            Material::emitter(name, emission)
        }
    };
    m.emission = emission;
    if m.base_color.max_element() > 1.0 {
        // Allowed (it is a teaching tool), but it creates energy and will make a furnace test fail.
        warnings.push(format!(
            "{}: material '{name}' reflects more than it receives (reflectance {} > 1)",
            ctx.path.display(),
            m.base_color.max_element()
        ));
    }
    Ok(m)
}
