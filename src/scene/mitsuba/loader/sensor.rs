//! Mitsuba 3's sensor onto mislab's camera and film: the perspective camera, its field of view, the film's size
//! and crop, and its reconstruction filter.

use super::*;

impl Loader {
    /// The film's `<rfilter>`: Mitsuba 3's box (radius 0.5), tent (`radius`, 1) and gaussian (`stddev`, 0.5; radius
    /// 4σ) are pbrt-v4's shapes; mitchell, catmullrom and lanczos become a gaussian of their radius, with a warning.
    pub(super) fn rfilter(&mut self, file: &Path, f: &Element) -> Result<(), SceneError> {
        let kind = self.attr(file, f, "type")?.unwrap_or_default();
        let sigma = self.float_prop(file, f, "stddev", 0.5)?;
        let (shape, radius) = match kind.as_str() {
            "box" => ("box", 0.5),
            "tent" => ("triangle", self.float_prop(file, f, "radius", 1.0)?),
            "gaussian" => ("gaussian", 4.0 * sigma),
            "mitchell" | "catmullrom" => ("gaussian", 2.0),
            "lanczos" => ("gaussian", self.int_prop(file, f, "lobes", 3)? as f32),
            other => return Err(self.err(file, f, format!("unknown <rfilter type=\"{}\">", clip(other, 40)))),
        };
        for (name, v) in [("radius", radius), ("stddev", sigma)] {
            if !(v.is_finite() && (0.05..=16.0).contains(&v)) {
                return Err(self.err(
                    file,
                    f,
                    format!("<rfilter type=\"{kind}\">: {name} {v} is out of range (0.05 to 16)"),
                ));
            }
        }
        let at = at(file, f.line);
        if !matches!(kind.as_str(), "box" | "tent" | "gaussian") {
            self.b.warnings.push(format!(
                "<rfilter type=\"{kind}\"> (at {at}) is rendered with a gaussian filter of radius {radius}, the nearest \
                 mislab has (it has no negative lobes)"
            ));
        }
        let source = format!("<rfilter type=\"{kind}\"> at {at}");
        self.b.scene.file_settings.filter = Some((FileFilter { shape, radius, sigma: sigma.min(16.0) }, source));
        Ok(())
    }

    pub(super) fn sensor(&mut self, file: &Path, e: &Element) -> Result<(), SceneError> {
        let ty = self.need(file, e, "type")?;
        if ty != "perspective" {
            self.b
                .ignore_at(format!("<sensor type=\"{}\"> (rendered as perspective)", clip(&ty, 40)), at(file, e.line));
        }
        let to_world = self.to_world(file, e)?;
        if !to_world.is_finite() || glam::DMat3::from_mat4(to_world).determinant() == 0.0 {
            return Err(self.err(file, e, "the sensor's to_world is singular (determinant 0): it cannot be inverted"));
        }
        let fov = self.float_prop(file, e, "fov", 90.0)? as f64;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err(file, e, format!("fov {fov} is outside (0, 180) degrees")));
        }
        let axis = match e.children.iter().find(|c| c.attr("name") == Some("fov_axis")) {
            Some(c) => self.need(file, c, "value")?,
            None => "x".into(),
        };
        let (mut w, mut h) = (768u32, 576u32);
        // Mitsuba 3's film crop: crop_offset_x/y (default 0) and crop_width/height (default the film's size).
        let (mut crop_offset, mut crop_size) = ([0u32; 2], [None::<u32>; 2]);
        let mut crop_at = None;
        if let Some(film) = e.children.iter().find(|c| c.tag == "film") {
            for c in &film.children {
                let v = |min: f64| -> Result<u32, SceneError> {
                    let n = self.numbers(file, c, &self.need(file, c, "value")?)?;
                    match n.first() {
                        Some(&v) if (min..=16384.0).contains(&v) && v.fract() == 0.0 => Ok(v as u32),
                        _ => Err(self.err(file, c, format!("film size must be an integer in {min}..=16384"))),
                    }
                };
                match c.attr("name") {
                    Some("width") => w = v(1.0)?,
                    Some("height") => h = v(1.0)?,
                    Some(name @ ("crop_offset_x" | "crop_offset_y")) => {
                        crop_offset[(name == "crop_offset_y") as usize] = v(0.0)?;
                        crop_at = Some(c);
                    }
                    Some(name @ ("crop_width" | "crop_height")) => {
                        crop_size[(name == "crop_height") as usize] = Some(v(1.0)?);
                        crop_at = Some(c);
                    }
                    _ => {}
                }
            }
            if let Some(f) = film.children.iter().find(|c| c.tag == "rfilter") {
                self.rfilter(file, f)?;
            }
        }
        if let Some(s) = e.children.iter().find(|c| c.tag == "sampler") {
            // Mitsuba 3's default sample_count is 4.
            let n = self.int_prop(file, s, "sample_count", 4)?;
            if !(1..=1 << 24).contains(&n) {
                return Err(self.err(file, s, format!("sample_count {n} is out of range")));
            }
            let kind = self.attr(file, s, "type")?.unwrap_or_default();
            let source = format!("<sampler type=\"{kind}\"> at {}", at(file, s.line));
            // Mitsuba 3's samplers, each as the nearest mislab has (its ldsampler is a (0,2)-sequence, as Sobol).
            let sampler = match kind.as_str() {
                "independent" => Some("independent"),
                "stratified" | "multijitter" | "orthogonal" => Some("stratified"),
                "ldsampler" => Some("sobol"),
                _ => None,
            };
            self.b.scene.file_settings.sampler = sampler.map(|s| (s, source.clone()));
            self.b.scene.file_settings.spp = Some((n as u32, source));
        }
        let aspect = w as f64 / h as f64;
        let half = (fov.to_radians() / 2.0).tan();
        let vhalf = match axis.as_str() {
            "x" => half / aspect,
            "y" => half,
            "diagonal" => half / (1.0 + aspect * aspect).sqrt(),
            "smaller" => {
                if aspect >= 1.0 {
                    half
                } else {
                    half / aspect
                }
            }
            "larger" => {
                if aspect >= 1.0 {
                    half / aspect
                } else {
                    half
                }
            }
            other => return Err(self.err(file, e, format!("unknown fov_axis '{other}'"))),
        };
        let position = to_world.transform_point3(DVec3::ZERO).as_vec3();
        let forward = to_world.transform_vector3(DVec3::Z).normalize().as_vec3();
        let up = to_world.transform_vector3(DVec3::Y).normalize().as_vec3();
        self.b.scene.camera =
            Camera { position, forward, up, vfov: (2.0 * vhalf.atan()) as f32, window: Camera::FULL_WINDOW };
        self.b.scene.film_size = Some([w, h]);
        if let Some(c) = crop_at {
            let [cw, ch] = [crop_size[0].unwrap_or(w), crop_size[1].unwrap_or(h)];
            let [ox, oy] = crop_offset;
            if ox + cw > w || oy + ch > h {
                return Err(self.err(
                    file,
                    c,
                    format!("the film crop ({cw}x{ch} at {ox}, {oy}) does not fit the {w}x{h} film"),
                ));
            }
            let (fw, fh) = (w as f32, h as f32);
            self.b.scene.camera.window = [ox as f32 / fw, (ox + cw) as f32 / fw, oy as f32 / fh, (oy + ch) as f32 / fh];
            self.b.scene.film_size = Some([cw, ch]);
            self.b.count("film crop (the image is that part of the film)", 1);
        }
        self.b.count("camera (perspective)", 1);
        for c in &e.children {
            if !matches!(c.tag.as_str(), "transform" | "film" | "sampler")
                && !matches!(c.attr("name"), Some("fov" | "fov_axis"))
            {
                self.b.ignore(format!("<sensor> property <{} name=\"{}\">", c.tag, c.attr("name").unwrap_or("")));
            }
        }
        Ok(())
    }
}
