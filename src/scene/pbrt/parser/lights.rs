//! pbrt-v4's `LightSource` directive onto mislab's lights: point, spot and distant lights, and the infinite light
//! (a constant or an environment map), each checked finite and with a non-negative `scale`.

use super::*;

impl Parser {
    pub(super) fn light(&mut self, kind: &str, p: &Params) -> Result<(), SceneError> {
        let to_world = self.mirror * self.gs.ctm;
        if !to_world.is_finite() || glam::DMat3::from_mat4(to_world).determinant() == 0.0 {
            return Err(p.error("the light's transform is singular (determinant 0)"));
        }
        let scale = light_scale(p)?;
        if p.has("power") || p.has("illuminance") {
            self.b.ignore(format!("LightSource \"{kind}\" \"power\"/\"illuminance\" (scale and L/I are used)"));
        }
        let point = |v: Option<Vec3>, d: Vec3| to_world.transform_point3(v.unwrap_or(d).as_dvec3()).as_vec3();
        match kind {
            "point" => {
                let i = self.spectrum(p, "I", Vec3::ONE)? * scale;
                let position = point(p.vec3("from", &["point3", "point"])?, Vec3::ZERO);
                self.b.scene.punctual_lights.push(PunctualLight::Point { position, intensity: i });
            }
            "spot" => {
                let i = self.spectrum(p, "I", Vec3::ONE)? * scale;
                let from = point(p.vec3("from", &["point3", "point"])?, Vec3::ZERO);
                let to = point(p.vec3("to", &["point3", "point"])?, Vec3::Z);
                let cone = p.float("coneangle", 30.0)?.to_radians();
                let delta = p.float("conedelta", 5.0)?.to_radians();
                self.b.scene.punctual_lights.push(PunctualLight::Spot {
                    position: from,
                    direction: (to - from).normalize_or(Vec3::NEG_Y),
                    intensity: i,
                    inner_cone: (cone - delta).max(0.0),
                    outer_cone: cone,
                });
            }
            "distant" => {
                let l = self.spectrum(p, "L", Vec3::ONE)? * scale;
                let from = p.vec3("from", &["point3", "point"])?.unwrap_or(Vec3::ZERO);
                let to = p.vec3("to", &["point3", "point"])?.unwrap_or(Vec3::Z);
                let dir = to_world.transform_vector3((to - from).as_dvec3()).as_vec3();
                if dir.length_squared() == 0.0 {
                    return Err(p.error("LightSource \"distant\": \"from\" and \"to\" are the same point"));
                }
                self.b
                    .scene
                    .punctual_lights
                    .push(PunctualLight::Directional { direction: dir.normalize(), irradiance: l });
            }
            "infinite" => {
                self.env_lights += 1;
                if self.env_lights > 1 {
                    self.b.ignore("a second LightSource \"infinite\" (mislab has one environment)");
                    for u in p.unused() {
                        p.has(u.trim_matches('"').split(' ').nth(1).unwrap_or(""));
                    }
                    return Ok(());
                }
                let light_from_world = Mat3::from_mat4(to_world.as_mat4()).inverse();
                if let Some(file) = p.string("filename")? {
                    let path = self.dir.resolve(&file, &p.file, p.line)?;
                    let by = at(&p.file, p.line);
                    let (w, h, texels) = load_float_image(&path, &by)?;
                    if w != h {
                        self.b.ignore("a non-square infinite light map (read as lat-long)");
                    }
                    let layout = if w == h { Layout::EqualArea } else { Layout::Equirect };
                    let map = env_import::resample(path, &texels, w, h, layout, light_from_world, ENV_HEIGHT);
                    self.b.scene.environment = Environment::Map { map: Arc::new(map), scale, rotation: 0.0 };
                    p.has("L");
                } else {
                    let l = self.spectrum(p, "L", Vec3::ONE)? * scale;
                    self.b.scene.environment = Environment::Constant(l);
                }
                p.has("portal");
            }
            _ => {
                self.b.ignore_at(format!("LightSource \"{}\"", clip(kind, 40)), at(&p.file, p.line));
                for u in p.unused() {
                    p.has(u.trim_matches('"').split(' ').nth(1).unwrap_or(""));
                }
                return Ok(());
            }
        }
        if !lights_are_finite(&self.b.scene) {
            return Err(p.error("the light's intensity, position or direction is out of the range of 32-bit floats"));
        }
        self.b.count(&format!("{kind} lights"), 1);
        Ok(())
    }
}

/// Whether every punctual light and the constant environment are finite (the importers check each light as
/// they add it, so a failure is the last one's).
fn lights_are_finite(scene: &Scene) -> bool {
    scene.punctual_lights.iter().all(crate::scene::punctual_light_is_finite)
        && !matches!(scene.environment, Environment::Constant(c) if !c.is_finite())
}

/// A light's `"float scale"`: finite and ≥ 0 (a negative one would make a light that absorbs).
pub(super) fn light_scale(p: &Params) -> Result<f32, SceneError> {
    let scale = p.float("scale", 1.0)?;
    if !(scale >= 0.0 && scale.is_finite()) {
        return Err(p.error(format!("a light's \"scale\" must be a finite number ≥ 0, not {scale}")));
    }
    Ok(scale)
}

/// A float RGB image for an environment: PFM (ours) or EXR (the image crate), top row first.
fn load_float_image(path: &Path, by: &str) -> Result<(u32, u32, Vec<[f32; 3]>), SceneError> {
    let bytes = read_bytes(path, by)?;
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let bad = |m: String| SceneError::new(path, format!("{m} (referenced by {by})"));
    let format = match ext.as_str() {
        "pfm" => return crate::scene::pfm::decode(&bytes).map(|p| (p.width, p.height, p.texels)).map_err(bad),
        "exr" => image::ImageFormat::OpenExr,
        "hdr" => image::ImageFormat::Hdr,
        _ => {
            let ext = clip(&ext, 20);
            return Err(bad(format!("unsupported environment map format '.{ext}' (expected .pfm, .exr or .hdr)")));
        }
    };
    let img = crate::scene::import_texture::decode_limited(&bytes, format).map_err(bad)?.to_rgb32f();
    Ok((img.width(), img.height(), img.pixels().map(|p| p.0).collect()))
}
