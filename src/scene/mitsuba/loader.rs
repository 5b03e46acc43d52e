//! Mitsuba 3 scene elements onto mislab's scene: transforms (`to_world` ops applied left to right), BSDFs (by
//! id, nested or referenced, `twosided` unwrapped), shapes, emitters and the sensor. Mitsuba's world is
//! right-handed and its camera looks down +z with +x to the left, so directions map over unchanged.

use super::xml::{self, Element};
use crate::io::input_file::clip;
use crate::scene::env_import::{self, Layout};
use crate::scene::import_build::{self, Builder, ObjectMesh};
use crate::scene::import_material::{MatParam, MaterialDesc, TexDesc};
use crate::scene::read_input::{at, included_from, read_bytes, SceneDir};
use crate::scene::{Camera, Environment, FileFilter, LoadOptions, PunctualLight, Scene, SceneError};
use glam::{DMat4, DVec3, Mat3, Vec3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Height of the lat-long map an environment is resampled into.
const ENV_HEIGHT: u32 = 512;

mod emitter;
mod sensor;

/// The loader's state.
pub struct Loader {
    main: PathBuf,
    dir: SceneDir,
    b: Builder,
    defaults: HashMap<String, String>,
    bsdfs: HashMap<String, usize>,
    /// Top-level `<emitter type="area" id=…>`s, which shapes take by `<ref id=…>` (Mitsuba 3 resolves references
    /// across the whole scene, so a shape may come before what it refers to).
    area_emitters: HashMap<String, (PathBuf, Element)>,
    /// Shapes whose references name nothing seen yet: read once the whole scene has been, with where they were.
    deferred: Vec<(PathBuf, String, Element)>,
    /// Where the file being read was included from ("" for the main file).
    included_by: String,
    includes: Vec<PathBuf>,
    default_material: usize,
    default_emitter_material: usize,
}

impl Loader {
    /// A loader for `main` (relative file names resolve against its directory, and may leave it only with
    /// `options.allow_outside_paths`).
    pub fn new(main: &Path, options: &LoadOptions) -> Loader {
        let mut b = Builder::default();
        let default_material = b.add_desc(MaterialDesc {
            name: "Mitsuba default (diffuse 0.5)".into(),
            kind: "diffuse".into(),
            params: BTreeMap::new(),
            at: String::new(),
        });
        // Mitsuba 3 gives a shape with an area emitter and no BSDF a black diffuse one (shape.cpp): a lamp reflects
        // nothing. With diffuse 0.5 there, a lamp above a floor relit the floor: +0.9 % in a test scene.
        let default_emitter_material = b.add_desc(MaterialDesc {
            name: "Mitsuba default for emitters (diffuse 0)".into(),
            kind: "diffuse".into(),
            params: BTreeMap::from([("reflectance".to_string(), MatParam::Rgb(Vec3::ZERO))]),
            at: String::new(),
        });
        Loader {
            main: main.into(),
            dir: SceneDir::of(main, options.allow_outside_paths),
            b,
            defaults: HashMap::new(),
            bsdfs: HashMap::new(),
            area_emitters: HashMap::new(),
            deferred: vec![],
            included_by: String::new(),
            includes: vec![],
            default_material,
            default_emitter_material,
        }
    }

    /// Reads the file and what it includes.
    pub fn run(mut self) -> Result<Scene, SceneError> {
        let main = self.main.clone();
        self.file(&main, "")?;
        for (file, by, e) in std::mem::take(&mut self.deferred) {
            self.shape(&file, &e).map_err(|err| included_from(&file, &by, err))?;
        }
        self.b.scene.name = main.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        Ok(self.b.finish("Mitsuba 3"))
    }

    fn file(&mut self, path: &Path, by: &str) -> Result<(), SceneError> {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.includes.contains(&canonical) {
            let chain: Vec<String> =
                self.includes.iter().chain([&canonical]).map(|p| p.display().to_string()).collect();
            return Err(SceneError::new(path, format!("circular include ({by}): {}", chain.join(" → "))));
        }
        if self.includes.len() >= 32 {
            return Err(SceneError::new(path, format!("includes nested more than 32 deep ({by})")));
        }
        let bytes = read_bytes(path, by)?;
        let text = String::from_utf8(bytes)
            .map_err(|_| SceneError::new(path, "not UTF-8 text: is this a Mitsuba XML file?"))?;
        // An error in an included file names that file and line, and where it was included from.
        let placed = |e| included_from(path, by, e);
        let root = xml::parse(path, &text).map_err(placed)?;
        if root.tag != "scene" {
            return Err(placed(SceneError::new(
                path,
                format!("line {}: the root element is <{}>, expected <scene>", root.line, clip(&root.tag, 40)),
            )));
        }
        self.includes.push(canonical);
        let outer = std::mem::replace(&mut self.included_by, by.to_string());
        let r = root.children.iter().try_for_each(|e| self.top(path, e)).map_err(placed);
        self.included_by = outer;
        self.includes.pop();
        r
    }

    fn err(&self, file: &Path, e: &Element, m: impl std::fmt::Display) -> SceneError {
        SceneError::new(file, format!("line {}: <{}>: {m}", e.line, e.tag))
    }

    /// An attribute with `$name` defaults substituted.
    fn attr(&self, file: &Path, e: &Element, name: &str) -> Result<Option<String>, SceneError> {
        let Some(v) = e.attr(name) else { return Ok(None) };
        if let Some(key) = v.strip_prefix('$') {
            return self
                .defaults
                .get(key)
                .cloned()
                .map(Some)
                .ok_or_else(|| self.err(file, e, format!("${key} has no <default name=\"{key}\">")));
        }
        Ok(Some(v.to_string()))
    }

    fn need(&self, file: &Path, e: &Element, name: &str) -> Result<String, SceneError> {
        self.attr(file, e, name)?.ok_or_else(|| self.err(file, e, format!("no '{name}' attribute")))
    }

    fn top(&mut self, file: &Path, e: &Element) -> Result<(), SceneError> {
        match e.tag.as_str() {
            "default" => {
                let (n, v) = (self.need(file, e, "name")?, self.need(file, e, "value")?);
                self.defaults.entry(n).or_insert(v);
            }
            "include" => {
                let f = self.need(file, e, "filename")?;
                let path = self.dir.resolve(&f, file, e.line)?;
                self.file(&path, &at(file, e.line))?;
            }
            "bsdf" => {
                let index = self.bsdf(file, e)?;
                if let Some(id) = e.attr("id") {
                    self.bsdfs.insert(id.to_string(), index);
                }
            }
            "shape" if !self.references_resolve(e) => {
                self.deferred.push((file.to_path_buf(), self.included_by.clone(), e.clone()))
            }
            "shape" => self.shape(file, e)?,
            "emitter" => self.emitter(file, e, None)?,
            "sensor" => self.sensor(file, e)?,
            "integrator"
                if matches!(
                    self.attr(file, e, "type")?.as_deref(),
                    Some("path" | "volpath" | "volpathmis" | "prb" | "ptracer")
                ) =>
            {
                // Mitsuba counts path vertices (2 is direct lighting; -1, its default, is unbounded); mislab bounces.
                let depth = self.int_prop(file, e, "max_depth", -1)?;
                let bounces = match depth {
                    -1 => 256,
                    d if (2..=257).contains(&d) => (d - 1) as u32,
                    d => return Err(self.err(file, e, format!("max_depth {d} is out of range (-1 or 2..=257)"))),
                };
                let t = self.attr(file, e, "type")?.unwrap_or_default();
                if t != "path" {
                    self.b.warnings.push(format!(
                        "<integrator type=\"{t}\"> ({}) is rendered as path tracing with the same depth",
                        at(file, e.line)
                    ));
                }
                let source = format!("<integrator type=\"{t}\"> at {}", at(file, e.line));
                self.b.scene.file_settings.max_depth = Some((bounces, source));
            }
            "integrator" | "sampler" | "film" | "rfilter" | "medium" | "phase" => {
                let t = clip(e.attr("type").unwrap_or(""), 40);
                self.b.ignore_at(format!("<{} type=\"{t}\">", e.tag), at(file, e.line));
            }
            "texture" => self.b.ignore("top-level <texture> (textures are read where they are used)"),
            other => return Err(self.err(file, e, format!("unknown element <{other}> in <scene>"))),
        }
        Ok(())
    }

    /// The `<integer name=NAME value=...>` child of `e`, or `default`.
    fn int_prop(&self, file: &Path, e: &Element, name: &str, default: i64) -> Result<i64, SceneError> {
        let Some(c) = e.children.iter().find(|c| c.tag == "integer" && c.attr("name") == Some(name)) else {
            return Ok(default);
        };
        let v = self.need(file, c, "value")?;
        v.trim().parse::<i64>().map_err(|_| self.err(file, c, format!("{name} '{}' is not an integer", clip(&v, 40))))
    }

    /// Numbers separated by spaces or commas; each must be a finite 32-bit float (Mitsuba's `Float`): 1e39 would
    /// become an infinity.
    fn numbers(&self, file: &Path, e: &Element, s: &str) -> Result<Vec<f64>, SceneError> {
        s.split(|c: char| c.is_whitespace() || c == ',')
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite() && v.abs() <= f32::MAX as f64))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| {
                self.err(file, e, format!("'{}' is not a list of finite numbers (of 32-bit float range)", clip(s, 80)))
            })
    }

    /// `<point>`/`<vector>`: `x`/`y`/`z` attributes or a `value`.
    fn xyz(&self, file: &Path, e: &Element, default: f64) -> Result<DVec3, SceneError> {
        if let Some(v) = self.attr(file, e, "value")? {
            let n = self.numbers(file, e, &v)?;
            return match n.len() {
                1 => Ok(DVec3::splat(n[0])),
                3 => Ok(DVec3::new(n[0], n[1], n[2])),
                k => Err(self.err(file, e, format!("'value' has {k} numbers; expected 1 or 3"))),
            };
        }
        let mut c = [default; 3];
        for (k, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some(s) = self.attr(file, e, a)? {
                c[k] = *self.numbers(file, e, &s)?.first().ok_or_else(|| self.err(file, e, format!("empty '{a}'")))?;
            }
        }
        Ok(DVec3::from_array(c))
    }

    /// A `<transform>`: its operations applied in order, each on the left.
    fn transform(&self, file: &Path, t: &Element) -> Result<DMat4, SceneError> {
        let mut m = DMat4::IDENTITY;
        for op in &t.children {
            let step = match op.tag.as_str() {
                "matrix" => {
                    let n = self.numbers(file, op, &self.need(file, op, "value")?)?;
                    match n.len() {
                        16 => DMat4::from_cols_array(&n.try_into().expect("16")).transpose(),
                        9 => DMat4::from_mat3(glam::DMat3::from_cols_array(&n.try_into().expect("9")).transpose()),
                        k => return Err(self.err(file, op, format!("matrix has {k} numbers; expected 16 or 9"))),
                    }
                }
                "translate" => DMat4::from_translation(self.xyz(file, op, 0.0)?),
                "scale" => DMat4::from_scale(self.xyz(file, op, 1.0)?),
                "rotate" => {
                    let axis = self.xyz(file, op, 0.0)?;
                    let angle: f64 = self
                        .numbers(file, op, &self.need(file, op, "angle")?)?
                        .first()
                        .copied()
                        .ok_or_else(|| self.err(file, op, "empty angle"))?;
                    let axis = axis.try_normalize().ok_or_else(|| self.err(file, op, "rotation about a zero axis"))?;
                    DMat4::from_axis_angle(axis, angle.to_radians())
                }
                "lookat" => {
                    let p = |n: &str| -> Result<DVec3, SceneError> {
                        let v = self.numbers(file, op, &self.need(file, op, n)?)?;
                        (v.len() == 3)
                            .then(|| DVec3::new(v[0], v[1], v[2]))
                            .ok_or_else(|| self.err(file, op, format!("'{n}' needs 3 numbers")))
                    };
                    let (origin, target) = (p("origin")?, p("target")?);
                    let up = if op.attr("up").is_some() { p("up")? } else { DVec3::Y };
                    let dir =
                        (target - origin).try_normalize().ok_or_else(|| self.err(file, op, "origin equals target"))?;
                    let left = up
                        .cross(dir)
                        .try_normalize()
                        .ok_or_else(|| self.err(file, op, "up is parallel to the view direction"))?;
                    let new_up = dir.cross(left);
                    DMat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0))
                }
                other => return Err(self.err(file, op, format!("unknown transform operation <{other}>"))),
            };
            m = step * m;
        }
        Ok(m)
    }

    fn to_world(&self, file: &Path, e: &Element) -> Result<DMat4, SceneError> {
        match e.children.iter().find(|c| c.tag == "transform") {
            Some(t) => self.transform(file, t),
            None => Ok(DMat4::IDENTITY),
        }
    }

    /// A property element as a material parameter.
    fn property(&mut self, file: &Path, c: &Element) -> Result<Option<(String, MatParam)>, SceneError> {
        let Some(name) = self.attr(file, c, "name")? else { return Ok(None) };
        let v = match c.tag.as_str() {
            "float" | "integer" => {
                let n = self.numbers(file, c, &self.need(file, c, "value")?)?;
                if n.len() != 1 {
                    return Err(self.err(file, c, format!("'{name}' needs one number, has {}", n.len())));
                }
                MatParam::Float(n[0] as f32)
            }
            "rgb" | "spectrum" | "color" => {
                let n = self.numbers(
                    file,
                    c,
                    &self.need(file, c, "value").or_else(|_| Ok::<_, SceneError>(String::new()))?,
                );
                match n {
                    Ok(n) if n.len() == 3 => MatParam::Rgb(Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32)),
                    Ok(n) if n.len() == 1 => MatParam::Rgb(Vec3::splat(n[0] as f32)),
                    _ if c.tag == "spectrum" => {
                        self.b.ignore(format!("<spectrum name=\"{name}\"> other than one value (white used)"));
                        MatParam::Rgb(Vec3::ONE)
                    }
                    Ok(n) => return Err(self.err(file, c, format!("'{name}' needs 3 numbers, has {}", n.len()))),
                    Err(e) => return Err(e),
                }
            }
            "string" => MatParam::Str(self.need(file, c, "value")?),
            "boolean" => MatParam::Bool(match self.need(file, c, "value")?.as_str() {
                "true" => true,
                "false" => false,
                v => return Err(self.err(file, c, format!("'{v}' is not true or false"))),
            }),
            "texture" => self.texture(file, c)?,
            "ref" => return Ok(None),
            _ => return Ok(None),
        };
        Ok(Some((name, v)))
    }

    fn texture(&mut self, file: &Path, t: &Element) -> Result<MatParam, SceneError> {
        let ty = self.attr(file, t, "type")?.unwrap_or_default();
        if ty != "bitmap" {
            self.b.ignore_at(format!("<texture type=\"{}\"> (grey 0.5 used)", clip(&ty, 40)), at(file, t.line));
            return Ok(MatParam::Rgb(Vec3::splat(0.5)));
        }
        let mut filename = None;
        let mut raw = false;
        let mut uv = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        for c in &t.children {
            match (c.tag.as_str(), c.attr("name")) {
                ("string", Some("filename")) => filename = Some(self.need(file, c, "value")?),
                ("boolean", Some("raw")) => raw = self.need(file, c, "value")? == "true",
                ("transform", Some("to_uv")) => {
                    let m = self.transform(file, c)?.as_mat4();
                    // Mitsuba's uv map acts on (u, v) before our v flip: v' = 1 − (m·(u, 1 − v_ours)).
                    let (a, b, tx) = (m.x_axis.x, m.y_axis.x, m.w_axis.x);
                    let (c2, d, ty2) = (m.x_axis.y, m.y_axis.y, m.w_axis.y);
                    uv = [[a, -b, tx + b], [-c2, d, 1.0 - ty2 - d]];
                }
                (tag, name) => {
                    self.b.ignore(format!("<texture type=\"bitmap\"> property <{tag} name=\"{}\">", name.unwrap_or("")))
                }
            }
        }
        let filename = filename.ok_or_else(|| self.err(file, t, "bitmap texture without a filename"))?;
        let path = self.dir.resolve(&filename, file, t.line)?;
        let referenced_by = at(file, t.line);
        if !path.is_file() {
            return Err(SceneError::new(&path, format!("texture file not found (referenced by {referenced_by})")));
        }
        Ok(MatParam::Texture(TexDesc { file: path, uv, scale: Vec3::ONE, srgb: !raw, referenced_by }))
    }

    /// A `<bsdf>` (any nesting of `twosided`) as a description; returns its index.
    fn bsdf(&mut self, file: &Path, e: &Element) -> Result<usize, SceneError> {
        let ty = self.need(file, e, "type")?;
        if ty == "twosided" {
            let inner = e
                .children
                .iter()
                .find(|c| c.tag == "bsdf")
                .ok_or_else(|| self.err(file, e, "twosided without a nested <bsdf>"))?;
            let i = self.bsdf(file, inner)?;
            if let Some(id) = e.attr("id") {
                self.b.descs[i].name = id.to_string();
            }
            return Ok(i);
        }
        let mut params = BTreeMap::new();
        for c in &e.children {
            if c.tag == "bsdf" {
                self.b.ignore(format!("nested <bsdf> inside <bsdf type=\"{ty}\">"));
                continue;
            }
            if let Some((n, v)) = self.property(file, c)? {
                params.insert(n, v);
            }
        }
        let name = e.attr("id").map(str::to_string).unwrap_or_else(|| format!("{}:{}", file.display(), e.line));
        Ok(self.b.add_desc(MaterialDesc { name, kind: ty, params, at: at(file, e.line) }))
    }

    /// Whether every `<ref id=…>` of a shape names a BSDF or area emitter already read.
    fn references_resolve(&self, e: &Element) -> bool {
        e.children.iter().filter(|c| c.tag == "ref").all(|c| {
            self.attr(Path::new(""), c, "id")
                .ok()
                .flatten()
                .is_some_and(|id| self.bsdfs.contains_key(&id) || self.area_emitters.contains_key(&id))
        })
    }

    fn shape(&mut self, file: &Path, e: &Element) -> Result<(), SceneError> {
        let ty = self.need(file, e, "type")?;
        let to_world = self.to_world(file, e)?;
        let mut material = None;
        let mut has_emitter = false;
        let mut emission = Vec3::ZERO;
        let mut flip = false;
        let mut filename = None;
        let (mut center, mut radius) = (DVec3::ZERO, 1.0f32);
        for c in &e.children {
            match c.tag.as_str() {
                "bsdf" => material = Some(self.bsdf(file, c)?),
                "ref" => {
                    let id = self.need(file, c, "id")?;
                    if let Some(&m) = self.bsdfs.get(&id) {
                        material = Some(m);
                    } else if let Some((emitter_file, emitter)) = self.area_emitters.get(&id).cloned() {
                        emission = self.radiance(&emitter_file, &emitter, "radiance")?;
                        has_emitter = true;
                    } else {
                        let what = format!("no <bsdf> or area <emitter> with id=\"{}\" in the scene", clip(&id, 40));
                        return Err(self.err(file, c, what));
                    }
                }
                "emitter" => {
                    let t = self.need(file, c, "type")?;
                    if t != "area" {
                        return Err(self.err(file, c, format!("emitter type \"{t}\" on a shape (expected area)")));
                    }
                    emission = self.radiance(file, c, "radiance")?;
                    has_emitter = true;
                }
                "transform" => {}
                "string" if c.attr("name") == Some("filename") => filename = Some(self.need(file, c, "value")?),
                "boolean" if c.attr("name") == Some("flip_normals") => flip = self.need(file, c, "value")? == "true",
                "point" if c.attr("name") == Some("center") => center = self.xyz(file, c, 0.0)?,
                "float" if c.attr("name") == Some("radius") => {
                    radius =
                        self.numbers(file, c, &self.need(file, c, "value")?)?.first().copied().unwrap_or(1.0) as f32
                }
                "boolean" | "string" | "float" | "integer" => {
                    self.b.ignore(format!("<shape type=\"{ty}\"> property '{}'", c.attr("name").unwrap_or("")))
                }
                other => self.b.ignore(format!("<{other}> inside <shape>")),
            }
        }
        let material =
            material.unwrap_or(if has_emitter { self.default_emitter_material } else { self.default_material });
        let by = at(file, e.line);
        let mesh: Option<ObjectMesh> = match ty.as_str() {
            "obj" | "ply" => {
                let f = filename.ok_or_else(|| self.err(file, e, format!("{ty} shape without a filename")))?;
                let path = self.dir.resolve(&f, file, e.line)?;
                let bytes = read_bytes(&path, &by)?;
                let m = if ty == "obj" {
                    crate::scene::obj::decode(&String::from_utf8_lossy(&bytes))
                } else {
                    crate::scene::ply::decode(&bytes)
                }
                .map_err(|m| SceneError::new(&path, format!("{m} (referenced by {by})")))?;
                Some(ObjectMesh { name: f, positions: m.positions, normals: m.normals, uvs: m.uvs, indices: m.indices })
            }
            "rectangle" => Some(import_build::rectangle()),
            "cube" => Some(import_build::cube()),
            "disk" => Some(import_build::disk(1.0, 0.0, false)),
            "sphere" => None,
            other => {
                self.b.ignore_at(format!("<shape type=\"{}\">", clip(other, 40)), at(file, e.line));
                return Ok(());
            }
        };
        // Mitsuba 3's area emitter is one-sided (its `twosided` adapter wraps BSDFs, not emitters).
        let Some(m) = self.b.material(material, emission, false)? else {
            self.b.invisible_shapes += 1;
            return Ok(());
        };
        let world = to_world.as_mat4();
        match mesh {
            Some(mut mesh) => {
                if flip {
                    for n in &mut mesh.normals {
                        *n = -*n;
                    }
                }
                let det_flip = Mat3::from_mat4(world).determinant() < 0.0;
                self.b.add_mesh(mesh, world, flip ^ det_flip, m).map_err(|m| self.err(file, e, m))?;
            }
            None => {
                if !(radius > 0.0) {
                    return Err(self.err(file, e, format!("sphere radius {radius} must be > 0")));
                }
                let to_world = world * glam::Mat4::from_translation(center.as_vec3());
                self.b.add_sphere(to_world, radius, m).map_err(|m| self.err(file, e, m))?;
            }
        }
        self.b.count(&format!("{ty} shapes"), 1);
        Ok(())
    }

    fn float_prop(&self, file: &Path, e: &Element, name: &str, default: f32) -> Result<f32, SceneError> {
        match e.children.iter().find(|c| c.attr("name") == Some(name)) {
            Some(c) => {
                let n = self.numbers(file, c, &self.need(file, c, "value")?)?;
                n.first().map(|v| *v as f32).ok_or_else(|| self.err(file, c, format!("'{name}' is empty")))
            }
            None => Ok(default),
        }
    }
}
