//! pbrt-v4 `Texture` directives and material parameters: image maps, `scale`, `constant` and 2D `checkerboard`
//! textures, RGB-valued parameters, and a `Material`'s typed parameter list with its textures resolved.

use super::Parser;
use crate::io::input_file::clip;
use crate::scene::import_material::{MatParam, MaterialDesc, TexDesc};
use crate::scene::pbrt::params::{Params, Values};
use crate::scene::read_input::at;
use crate::scene::SceneError;
use glam::Vec3;

impl Parser {
    /// An RGB-valued parameter (`rgb`, `blackbody` approximated as white, named spectra as white).
    pub(super) fn spectrum(&mut self, p: &Params, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        match p.type_of(name) {
            Some("rgb") | Some("color") => Ok(p.vec3(name, &["rgb", "color"])?.unwrap_or(default)),
            Some(ty) => {
                if let Some(q) = p.list.iter().rev().find(|q| q.name == name) {
                    if let Values::Strs(s) = &q.values {
                        self.named_spectrum(p, q.line, s.first().map_or("", String::as_str))?;
                    }
                }
                p.has(name);
                self.b.ignore(format!("\"{ty} {name}\" spectra (white of the same luminance 1 used)"));
                Ok(Vec3::ONE)
            }
            None => Ok(default),
        }
    }

    /// A `"spectrum"` parameter's name: one of pbrt-v4's named spectra, or a spectrum file in the scene's folder
    /// (whose values mislab does not read: the caller approximates and says so). Anything else is an error at
    /// `line`, as pbrt-v4 refuses it.
    pub(super) fn named_spectrum(&mut self, p: &Params, line: usize, name: &str) -> Result<(), SceneError> {
        if crate::scene::named_spectra::is_pbrt_name(name) {
            return Ok(());
        }
        let file = self.dir.resolve(name, &p.file, line)?;
        if file.is_file() {
            self.b.ignore_at(format!("spectrum file \"{}\" (white used)", clip(name, 60)), at(&p.file, line));
            return Ok(());
        }
        Err(SceneError::new(
            &p.file,
            format!(
                "line {line}: unknown named spectrum \"{}\" (neither one of pbrt-v4's named spectra nor a spectrum file)",
                clip(name, 60)
            ),
        ))
    }

    pub(super) fn texture(&mut self, name: &str, _ty: &str, class: &str, p: &Params) -> Result<(), SceneError> {
        let value = match class {
            "imagemap" => {
                let file = p
                    .string("filename")?
                    .ok_or_else(|| p.error(format!("Texture \"{name}\": no \"string filename\"")))?;
                let path = self.dir.resolve(&file, &p.file, p.line)?;
                let referenced_by = at(&p.file, p.line);
                if !path.is_file() {
                    return Err(SceneError::new(
                        &path,
                        format!("texture file not found (referenced by {referenced_by})"),
                    ));
                }
                let (us, vs) = (p.float("uscale", 1.0)?, p.float("vscale", 1.0)?);
                let (ud, vd) = (p.float("udelta", 0.0)?, p.float("vdelta", 0.0)?);
                let scale = p.float("scale", 1.0)?;
                let encoding = p.string("encoding")?.unwrap_or_else(|| "sRGB".into());
                if p.bool("invert", false)? {
                    self.b.ignore(format!("Texture \"{name}\" \"bool invert\""));
                }
                p.has("filter");
                // Stored with v down; our add_mesh already flips v, so the pbrt map (us·u+ud, vs·v+vd) becomes
                // u' = us·u + ud, v' = vs·v' − vs + 1 − vd in terms of the flipped v' = 1 − v.
                let uv = [[us, 0.0, ud], [0.0, vs, 1.0 - vs - vd]];
                MatParam::Texture(TexDesc {
                    file: path,
                    uv,
                    scale: Vec3::splat(scale),
                    srgb: encoding != "linear",
                    referenced_by,
                })
            }
            "scale" => {
                let base = self.texture_or_value(p, "tex", Vec3::ONE)?;
                let s = match self.texture_or_value(p, "scale", Vec3::ONE)? {
                    MatParam::Rgb(c) => c,
                    MatParam::Float(f) => Vec3::splat(f),
                    _ => {
                        self.b.ignore(format!("Texture \"{name}\" \"scale\" by a texture"));
                        Vec3::ONE
                    }
                };
                match base {
                    MatParam::Texture(mut t) => {
                        t.scale *= s;
                        MatParam::Texture(t)
                    }
                    MatParam::Checkerboard { tex1, tex2, uv } => {
                        MatParam::Checkerboard { tex1: tex1 * s, tex2: tex2 * s, uv }
                    }
                    MatParam::Rgb(c) => MatParam::Rgb(c * s),
                    MatParam::Float(f) => MatParam::Rgb(f * s),
                    other => other,
                }
            }
            "constant" => self.texture_or_value(p, "value", Vec3::ONE)?,
            "checkerboard" => self.checkerboard(name, p)?,
            _ => {
                self.b.ignore_at(format!("Texture class \"{}\" (grey 0.5 used)", clip(class, 40)), at(&p.file, p.line));
                MatParam::Rgb(Vec3::splat(0.5))
            }
        };
        for u in p.unused() {
            self.b.ignore(format!("Texture \"{class}\" parameter {u}"));
        }
        self.textures.insert(name.to_string(), value);
        Ok(())
    }

    /// pbrt-v4's 2D `checkerboard` (tex1 = 1, tex2 = 0 by default) under its `uv` mapping
    /// (s, t) = (uscale·u + udelta, vscale·v + vdelta), evaluated on the device per sample (no filtering).
    pub(super) fn checkerboard(&mut self, name: &str, p: &Params) -> Result<MatParam, SceneError> {
        let mut value = |key: &str, default: f32| -> Result<Vec3, SceneError> {
            Ok(match self.texture_or_value(p, key, Vec3::splat(default))? {
                MatParam::Rgb(c) => c,
                MatParam::Float(f) => Vec3::splat(f),
                _ => {
                    self.b.ignore(format!("Texture \"{name}\" \"{key}\" as a texture ({default} used)"));
                    Vec3::splat(default)
                }
            })
        };
        let (tex1, tex2) = (value("tex1", 1.0)?, value("tex2", 0.0)?);
        if p.int("dimension", 2)? != 2 {
            self.b.ignore(format!("Texture \"{name}\": a 3D checkerboard (grey 0.5 used)"));
            return Ok(MatParam::Rgb(Vec3::splat(0.5)));
        }
        if let Some(m) = p.string("mapping")?.filter(|m| m != "uv") {
            self.b.ignore(format!("Texture \"{name}\" \"mapping\" \"{m}\" (the uv mapping used)"));
        }
        let (us, vs) = (p.float("uscale", 1.0)?, p.float("vscale", 1.0)?);
        let (ud, vd) = (p.float("udelta", 0.0)?, p.float("vdelta", 0.0)?);
        // In terms of mislab's flipped v' = 1 − v (add_mesh): t = vs·v + vd = −vs·v' + vs + vd.
        let uv = [[us, 0.0, ud], [0.0, -vs, vs + vd]];
        Ok(MatParam::Checkerboard { tex1, tex2, uv })
    }

    pub(super) fn texture_or_value(&mut self, p: &Params, name: &str, default: Vec3) -> Result<MatParam, SceneError> {
        match p.type_of(name) {
            Some("texture") => {
                let t = p.string_of(name, &["texture"])?.expect("present");
                self.textures.get(&t).cloned().ok_or_else(|| p.error(format!("texture \"{t}\" is not defined")))
            }
            Some("float") => Ok(MatParam::Float(p.float(name, 1.0)?)),
            Some(_) => Ok(MatParam::Rgb(self.spectrum(p, name, default)?)),
            None => Ok(MatParam::Rgb(default)),
        }
    }

    /// A material description: every parameter, typed, textures resolved.
    pub(super) fn material_desc(&mut self, name: &str, kind: &str, p: &Params) -> Result<MaterialDesc, SceneError> {
        let mut params = std::collections::BTreeMap::new();
        for q in &p.list {
            p.has(&q.name);
            if q.name == "type" {
                continue;
            }
            let v = match (&q.ty[..], &q.values) {
                ("texture", Values::Strs(s)) if s.len() == 1 => self
                    .textures
                    .get(&s[0])
                    .cloned()
                    .ok_or_else(|| p.error_at(q, format!("texture \"{}\" is not defined", s[0])))?,
                ("float" | "integer", Values::Nums(v)) if v.len() == 1 => MatParam::Float(v[0] as f32),
                ("rgb" | "color", Values::Nums(v)) if v.len() == 3 => {
                    MatParam::Rgb(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
                }
                ("spectrum", Values::Strs(s)) if s.len() == 1 => {
                    self.named_spectrum(p, q.line, &s[0])?;
                    MatParam::Spectrum(s[0].clone())
                }
                ("spectrum" | "blackbody", Values::Nums(_)) => MatParam::Spectrum(format!("{} values", q.ty)),
                ("string", Values::Strs(s)) if s.len() == 1 => MatParam::Str(s[0].clone()),
                ("bool", Values::Bools(b)) if b.len() == 1 => MatParam::Bool(b[0]),
                _ => return Err(p.error_at(q, "wrong type or number of values for a material parameter")),
            };
            params.insert(q.name.clone(), v);
        }
        Ok(MaterialDesc { name: name.into(), kind: kind.into(), params, at: at(&p.file, p.line) })
    }
}
