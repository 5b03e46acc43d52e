//! Mitsuba 3 emitters onto mislab's lights: area emitters' radiance, the constant and map environments, point,
//! spot and directional lights.

use super::*;

impl Loader {
    /// An emitter's radiance (or intensity, irradiance): finite and ≥ 0 in every channel, as Mitsuba 3 refuses a
    /// negative emitter spectrum.
    pub(super) fn radiance(&mut self, file: &Path, e: &Element, name: &str) -> Result<Vec3, SceneError> {
        let mut v = Vec3::ONE;
        for c in &e.children {
            if c.attr("name") == Some(name) {
                match self.property(file, c)? {
                    Some((_, MatParam::Rgb(c))) => v = c,
                    Some((_, MatParam::Float(f))) => v = Vec3::splat(f),
                    _ => return Err(self.err(file, c, format!("'{name}' must be an rgb or spectrum value"))),
                }
                if !(v.min_element() >= 0.0 && v.is_finite()) {
                    return Err(self.err(
                        file,
                        c,
                        format!("'{name}' {v} is negative or not finite (emitted light is ≥ 0)"),
                    ));
                }
            }
        }
        Ok(v)
    }

    pub(super) fn emitter(&mut self, file: &Path, e: &Element, _: Option<()>) -> Result<(), SceneError> {
        let ty = self.need(file, e, "type")?;
        let to_world = self.to_world(file, e)?;
        let scale = self.float_prop(file, e, "scale", 1.0)?;
        if !(scale >= 0.0) {
            return Err(self.err(file, e, format!("an emitter's 'scale' must be ≥ 0, not {scale}")));
        }
        match ty.as_str() {
            "constant" => self.b.scene.environment = Environment::Constant(self.radiance(file, e, "radiance")? * scale),
            "envmap" => {
                let f = e
                    .children
                    .iter()
                    .find(|c| c.attr("name") == Some("filename"))
                    .ok_or_else(|| self.err(file, e, "envmap without a filename"))?;
                let path = self.dir.resolve(&self.need(file, f, "value")?, file, f.line)?;
                let by = at(file, e.line);
                let bytes = read_bytes(&path, &by)?;
                let format = image::guess_format(&bytes).unwrap_or(image::ImageFormat::Hdr);
                let img = crate::scene::import_texture::decode_limited(&bytes, format)
                    .map_err(|er| SceneError::new(&path, format!("{er} (referenced by {by})")))?
                    .to_rgb32f();
                let texels: Vec<[f32; 3]> = img.pixels().map(|p| p.0).collect();
                // Mitsuba's lat-long (envmap.cpp): u = atan2(x, −z)/2π wrapped to [0, 1), v = acos(y)/π in its
                // local frame; mislab's is the same but for u + ½ (u = ½ looks down −z). So a Mitsuba direction is
                // mislab's turned half a turn about +y, after the inverse of its to_world. Checked against Mitsuba
                // 3 itself: an envmap seen directly, rotated 60° about y, went from 0.16 to 5e-6 block relMSE.
                let half_turn = Mat3::from_rotation_y(std::f32::consts::PI);
                let light_from_world = half_turn * Mat3::from_mat4(to_world.as_mat4()).inverse();
                let map = env_import::resample(
                    path,
                    &texels,
                    img.width(),
                    img.height(),
                    Layout::Equirect,
                    light_from_world,
                    ENV_HEIGHT,
                );
                self.b.scene.environment = Environment::Map { map: Arc::new(map), scale, rotation: 0.0 };
            }
            "point" => {
                let mut position = to_world.transform_point3(DVec3::ZERO);
                if let Some(p) = e.children.iter().find(|c| c.attr("name") == Some("position")) {
                    position = self.xyz(file, p, 0.0)?;
                }
                let intensity = self.radiance(file, e, "intensity")? * scale;
                self.b.scene.punctual_lights.push(PunctualLight::Point { position: position.as_vec3(), intensity });
            }
            "spot" => {
                let intensity = self.radiance(file, e, "intensity")? * scale;
                let cutoff = self.float_prop(file, e, "cutoff_angle", 20.0)?;
                let beam = self.float_prop(file, e, "beam_width", cutoff * 0.75)?;
                self.b.scene.punctual_lights.push(PunctualLight::Spot {
                    position: to_world.transform_point3(DVec3::ZERO).as_vec3(),
                    direction: to_world.transform_vector3(DVec3::Z).normalize().as_vec3(),
                    intensity,
                    inner_cone: beam.to_radians(),
                    outer_cone: cutoff.to_radians(),
                });
            }
            "directional" => {
                let irradiance = self.radiance(file, e, "irradiance")? * scale;
                let mut d = to_world.transform_vector3(DVec3::Z);
                if let Some(p) = e.children.iter().find(|c| c.attr("name") == Some("direction")) {
                    d = self.xyz(file, p, 0.0)?;
                }
                let direction = d.try_normalize().ok_or_else(|| self.err(file, e, "zero direction"))?.as_vec3();
                self.b.scene.punctual_lights.push(PunctualLight::Directional { direction, irradiance });
            }
            "area" => match e.attr("id") {
                // Named, for shapes to take by reference.
                Some(id) => {
                    self.radiance(file, e, "radiance")?;
                    self.area_emitters.insert(id.to_string(), (file.to_path_buf(), e.clone()));
                    return Ok(());
                }
                None => return Err(self.err(file, e, "an area emitter must be inside a <shape> or have an id")),
            },
            other => {
                self.b.ignore_at(format!("<emitter type=\"{}\">", clip(other, 40)), at(file, e.line));
                return Ok(());
            }
        }
        self.b.count(&format!("{ty} emitters"), 1);
        Ok(())
    }
}
