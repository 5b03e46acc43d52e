//! pbrt-v4 directives and graphics state: transforms, attribute stacks, named materials and textures, area
//! lights, object instancing (flattened into triangles), Include/Import (with circular-include detection),
//! camera, film and lights.
//!
//! pbrt-v4's own rules are kept, with an error naming the file and line where pbrt-v4 refuses a scene (its
//! `VERIFY_OPTIONS` / `VERIFY_WORLD`: options after `WorldBegin`, scene description before it, a second
//! `WorldBegin`; negative RGB values; unknown camera and film types; unknown named spectra), and a warning where
//! pbrt-v4 renders and mislab approximates. File names (Include, textures, meshes, maps) must stay inside the
//! scene's folder unless `--allow-outside-paths` (`read_input::SceneDir`).

use super::params::{self, Params};
use super::shapes;
use super::tokenizer::{tokenize, Tok, Token};
use crate::io::input_file::clip;
use crate::scene::env_import::{self, Layout};
use crate::scene::import_build::{Builder, ObjectMesh};
use crate::scene::import_material::{MatParam, MaterialDesc};
use crate::scene::read_input::{at, included_from, read_bytes, SceneDir};
use crate::scene::{Camera, Environment, FileFilter, LoadOptions, PunctualLight, Scene, SceneError};
use glam::{DMat4, DVec3, Mat3, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

mod film;
mod lights;
mod shape;
mod textures;

/// pbrt's world → mislab's when pbrt's camera frame is a proper rotation (a `LookAt`, say). pbrt's camera space
/// is left-handed (x right, y up, z forward: x = up × forward), mislab's right-handed (right = forward × up), so
/// such a camera would see the world mirrored; mirroring the whole world in x (geometry, lights, camera) gives
/// pbrt's picture. A camera transform that already swaps handedness (the Bitterli files' `Transform`s, or the
/// usual `Scale -1 1 1`) needs none: those scenes render unmirrored against their references.
const MIRROR_X: DMat4 =
    DMat4::from_cols_array(&[-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);

/// Nesting depth of Include / Import beyond which a file is refused.
const MAX_INCLUDE_DEPTH: usize = 32;

/// Height of the lat-long map an environment is resampled into.
const ENV_HEIGHT: u32 = 512;

#[derive(Clone)]
struct AreaLight {
    radiance: Vec3,
    two_sided: bool,
}

#[derive(Clone)]
struct State {
    ctm: DMat4,
    reverse: bool,
    material: usize,
    area: Option<AreaLight>,
}

/// A shape with the state it was declared in (kept for object instances).
#[derive(Clone)]
struct ShapeCall {
    kind: String,
    params: Rc<Params>,
    ctm: DMat4,
    reverse: bool,
    material: usize,
    area: Option<AreaLight>,
}

#[derive(PartialEq)]
enum Scope {
    Attribute,
    Transform,
    Object,
}

/// Directives pbrt-v4 takes only before `WorldBegin` (its `VERIFY_OPTIONS`).
const OPTIONS_ONLY: &[&str] =
    &["Camera", "Sampler", "Film", "PixelFilter", "Accelerator", "Integrator", "TransformTimes", "WorldBegin"];
/// Directives pbrt-v4 takes only after `WorldBegin` (its `VERIFY_WORLD`; TransformBegin/End are its
/// AttributeBegin/End).
const WORLD_ONLY: &[&str] = &[
    "ReverseOrientation",
    "AttributeBegin",
    "AttributeEnd",
    "TransformBegin",
    "TransformEnd",
    "LightSource",
    "Shape",
    "ObjectBegin",
    "ObjectEnd",
    "ObjectInstance",
    "Texture",
    "Material",
    "MakeNamedMaterial",
    "NamedMaterial",
    "AreaLightSource",
];
/// pbrt-v4's camera and film types (others are an error there).
const CAMERAS: &[&str] = &["perspective", "orthographic", "realistic", "spherical"];
const FILMS: &[&str] = &["rgb", "gbuffer", "spectral"];

/// The parser and everything it has built so far.
pub struct Parser {
    main: PathBuf,
    dir: SceneDir,
    /// Where `WorldBegin` was, once it was.
    world: Option<String>,
    b: Builder,
    gs: State,
    stack: Vec<(State, Scope, PathBuf, usize)>,
    named_materials: HashMap<String, usize>,
    textures: HashMap<String, MatParam>,
    objects: HashMap<String, Vec<ShapeCall>>,
    object: Option<(String, Vec<ShapeCall>)>,
    includes: Vec<PathBuf>,
    camera: Option<(DMat4, f64)>,
    film: [u32; 2],
    /// The film's crop, in pixels `[x0, x1, y0, y1]` (`parser/film.rs`).
    crop: Option<[u32; 4]>,
    env_lights: usize,
    /// pbrt's world → mislab's: the identity, or MIRROR_X under a camera that keeps pbrt's left-handed frame.
    mirror: DMat4,
}

/// pbrt-v4 integrators that estimate the same light transport as path tracing: mislab renders them as path
/// tracing with their `maxdepth` (others, such as "ambientocclusion", are ignored with a warning).
const INTEGRATORS_AS_PATHS: &[&str] =
    &["path", "volpath", "bdpt", "mlt", "sppm", "simplepath", "simplevolpath", "randomwalk", "lightpath"];

impl Parser {
    /// A parser for the file at `main` (relative paths in it resolve against its directory, as in pbrt, and may
    /// leave it only with `options.allow_outside_paths`).
    pub fn new(main: &Path, options: &LoadOptions) -> Parser {
        let mut b = Builder::default();
        let default = b.add_desc(MaterialDesc {
            name: "pbrt default (diffuse 0.5)".into(),
            kind: "diffuse".into(),
            params: Default::default(),
            at: String::new(),
        });
        Parser {
            main: main.to_path_buf(),
            dir: SceneDir::of(main, options.allow_outside_paths),
            world: None,
            b,
            gs: State { ctm: DMat4::IDENTITY, reverse: false, material: default, area: None },
            stack: vec![],
            named_materials: HashMap::new(),
            textures: HashMap::new(),
            objects: HashMap::new(),
            object: None,
            includes: vec![],
            camera: None,
            film: [1280, 720],
            crop: None,
            env_lights: 0,
            mirror: DMat4::IDENTITY,
        }
    }

    /// Parses the file and everything it includes, and returns the scene.
    pub fn run(mut self) -> Result<Scene, SceneError> {
        let main = self.main.clone();
        self.file(&main, "")?;
        if let Some((_, scope, file, line)) = self.stack.last() {
            let what = match scope {
                Scope::Attribute => "AttributeBegin",
                Scope::Transform => "TransformBegin",
                Scope::Object => "ObjectBegin",
            };
            return Err(SceneError::new(file, format!("line {line}: {what} is never closed (is the file truncated?)")));
        }
        if self.world.is_none() {
            // pbrt-v4: "End of files before WorldBegin".
            return Err(SceneError::new(
                &main,
                "the file ends before WorldBegin: a pbrt-v4 scene describes its world after WorldBegin",
            ));
        }
        let [w, h] = self.film;
        let mut scene_camera = Camera::default();
        if let Some((camera_from_world, fov)) = self.camera {
            let wfc = self.mirror * camera_from_world.inverse();
            let finite = |v: Vec3| v.is_finite();
            let position = wfc.transform_point3(DVec3::ZERO).as_vec3();
            let forward = wfc.transform_vector3(DVec3::Z).normalize().as_vec3();
            let up = wfc.transform_vector3(DVec3::Y).normalize().as_vec3();
            // pbrt's fov spans the shorter image axis; ours is vertical.
            let half = (fov.to_radians() / 2.0).tan();
            let vfov = if w >= h { fov.to_radians() } else { 2.0 * (half * h as f64 / w as f64).atan() };
            if !(finite(position) && finite(forward) && finite(up)) {
                return Err(SceneError::new(
                    &main,
                    "the camera's position or direction is out of the range of 32-bit floats",
                ));
            }
            scene_camera = Camera { position, forward, up, vfov: vfov as f32, window: Camera::FULL_WINDOW };
            self.b.count("camera (perspective)", 1);
        } else {
            self.b.ignore("no Camera directive: mislab's default camera is used");
        }
        self.b.scene.camera = scene_camera;
        self.b.scene.film_size = Some([w, h]);
        if let Some([x0, x1, y0, y1]) = self.crop {
            let (fw, fh) = (w as f32, h as f32);
            self.b.scene.camera.window = [x0 as f32 / fw, x1 as f32 / fw, y0 as f32 / fh, y1 as f32 / fh];
            self.b.scene.film_size = Some([x1 - x0, y1 - y0]);
        }
        self.b.scene.name = self.main.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        Ok(self.b.finish("pbrt-v4"))
    }

    fn file(&mut self, path: &Path, by: &str) -> Result<(), SceneError> {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.includes.contains(&canonical) {
            let chain: Vec<String> =
                self.includes.iter().chain([&canonical]).map(|p| p.display().to_string()).collect();
            return Err(SceneError::new(path, format!("circular Include ({by}): {}", chain.join(" → "))));
        }
        if self.includes.len() >= MAX_INCLUDE_DEPTH {
            return Err(SceneError::new(path, format!("Include nested more than {MAX_INCLUDE_DEPTH} deep ({by})")));
        }
        let bytes = read_bytes(path, by)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            SceneError::new(
                path,
                format!("not UTF-8 text (byte {}): is this a pbrt file?", e.utf8_error().valid_up_to()),
            )
        })?;
        // An error in an included file names that file and line, and where it was included from.
        let placed = |e| included_from(path, by, e);
        let tokens = tokenize(path, &text).map_err(placed)?;
        self.includes.push(canonical);
        let r = self.tokens(path, &tokens).map_err(placed);
        self.includes.pop();
        r
    }

    fn tokens(&mut self, file: &Path, t: &[Token]) -> Result<(), SceneError> {
        let mut i = 0;
        while i < t.len() {
            let line = t[i].line;
            let err = |m: String| SceneError::new(file, format!("line {line}: {m}"));
            let Tok::Word(d) = &t[i].tok else {
                // What was found, not its text: a file that is not pbrt at all is not echoed.
                let found = match &t[i].tok {
                    Tok::Str(_) => "a quoted string",
                    Tok::Num(_) => "a number",
                    _ => "a bracket",
                };
                return Err(err(format!("expected a directive, found {found}")));
            };
            let d = d.clone();
            i += 1;
            if self.world.is_some() && OPTIONS_ONLY.contains(&d.as_str()) {
                let first = self.world.as_deref().unwrap_or("");
                return Err(err(if d == "WorldBegin" {
                    format!("a second WorldBegin (the first is at {first})")
                } else {
                    format!("{d} after WorldBegin (at {first}): pbrt-v4 takes it only before WorldBegin")
                }));
            }
            if self.world.is_none() && WORLD_ONLY.contains(&d.as_str()) {
                return Err(err(format!("{d} before WorldBegin: pbrt-v4 takes it only after WorldBegin")));
            }
            let nums = |n: usize, i: &mut usize| -> Result<Vec<f64>, SceneError> {
                let bracket = matches!(t.get(*i).map(|t| &t.tok), Some(Tok::Open));
                if bracket {
                    *i += 1;
                }
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    match t.get(*i).map(|t| &t.tok) {
                        Some(Tok::Num(x)) => v.push(*x),
                        _ => return Err(err(format!("{d} expects {n} numbers"))),
                    }
                    *i += 1;
                }
                if bracket {
                    if !matches!(t.get(*i).map(|t| &t.tok), Some(Tok::Close)) {
                        return Err(err(format!("{d} expects {n} numbers in [ ]")));
                    }
                    *i += 1;
                }
                Ok(v)
            };
            let string = |i: &mut usize| -> Result<String, SceneError> {
                match t.get(*i).map(|t| &t.tok) {
                    Some(Tok::Str(s)) => {
                        *i += 1;
                        Ok(s.clone())
                    }
                    _ => Err(err(format!("{d} expects a quoted name"))),
                }
            };
            match d.as_str() {
                "AttributeBegin" => self.stack.push((self.gs.clone(), Scope::Attribute, file.into(), line)),
                "TransformBegin" => self.stack.push((self.gs.clone(), Scope::Transform, file.into(), line)),
                "AttributeEnd" | "TransformEnd" => {
                    let want = if d == "AttributeEnd" { Scope::Attribute } else { Scope::Transform };
                    match self.stack.pop() {
                        Some((s, scope, ..)) if scope == want => {
                            if want == Scope::Attribute {
                                self.gs = s;
                            } else {
                                self.gs.ctm = s.ctm;
                            }
                        }
                        _ => return Err(err(format!("{d} without a matching {}Begin", &d[..d.len() - 3]))),
                    }
                }
                "WorldBegin" => {
                    self.gs.ctm = DMat4::IDENTITY;
                    self.world = Some(at(file, line));
                }
                "WorldEnd" => {}
                "Identity" => self.gs.ctm = DMat4::IDENTITY,
                "Translate" => {
                    let v = nums(3, &mut i)?;
                    self.gs.ctm *= DMat4::from_translation(DVec3::new(v[0], v[1], v[2]));
                }
                "Scale" => {
                    let v = nums(3, &mut i)?;
                    self.gs.ctm *= DMat4::from_scale(DVec3::new(v[0], v[1], v[2]));
                }
                "Rotate" => {
                    let v = nums(4, &mut i)?;
                    let axis = DVec3::new(v[1], v[2], v[3]);
                    if axis.length_squared() == 0.0 {
                        return Err(err("Rotate about a zero axis".into()));
                    }
                    self.gs.ctm *= DMat4::from_axis_angle(axis.normalize(), v[0].to_radians());
                }
                "LookAt" => {
                    let v = nums(9, &mut i)?;
                    self.gs.ctm *= look_at(&v).ok_or_else(|| err("LookAt: degenerate eye, target and up".into()))?;
                }
                "Transform" | "ConcatTransform" => {
                    let v = nums(16, &mut i)?;
                    let m = DMat4::from_cols_array(&v.try_into().expect("16 numbers"));
                    if d == "Transform" {
                        self.gs.ctm = m;
                    } else {
                        self.gs.ctm *= m;
                    }
                }
                "ReverseOrientation" => self.gs.reverse = !self.gs.reverse,
                "Include" | "Import" => {
                    let name = string(&mut i)?;
                    let path = self.dir.resolve(&name, file, line)?;
                    self.file(&path, &at(file, line))?;
                }
                "ObjectBegin" => {
                    let name = string(&mut i)?;
                    if self.object.is_some() {
                        return Err(err("ObjectBegin inside another ObjectBegin".into()));
                    }
                    self.stack.push((self.gs.clone(), Scope::Object, file.into(), line));
                    self.object = Some((name, vec![]));
                }
                "ObjectEnd" => {
                    let Some((name, shapes)) = self.object.take() else {
                        return Err(err("ObjectEnd without ObjectBegin".into()));
                    };
                    match self.stack.pop() {
                        Some((s, Scope::Object, ..)) => self.gs = s,
                        _ => return Err(err("ObjectEnd does not close its ObjectBegin".into())),
                    }
                    self.objects.insert(name, shapes);
                }
                "ObjectInstance" => {
                    let name = string(&mut i)?;
                    if self.object.is_some() {
                        return Err(err("ObjectInstance inside an object definition (ObjectBegin)".into()));
                    }
                    let Some(shapes) = self.objects.get(&name).cloned() else {
                        return Err(err(format!("ObjectInstance \"{name}\": no such object (ObjectBegin)")));
                    };
                    self.b.count("object instances (flattened)", 1);
                    for mut s in shapes {
                        s.ctm = self.gs.ctm * s.ctm;
                        self.shape(s)?;
                    }
                }
                _ => {
                    // Directives with a type name and a parameter list.
                    let has_kind = !matches!(d.as_str(), "Attribute");
                    let kind = if has_kind { string(&mut i)? } else { String::new() };
                    let mut extra = None;
                    if d == "Texture" || d == "MediumInterface" || d == "Attribute" {
                        // Texture "name" "type" "class"; MediumInterface "in" ["out"]; Attribute "target".
                        if let Some(Tok::Str(s)) = t.get(i).map(|t| &t.tok) {
                            if d != "MediumInterface" || !s.contains(' ') {
                                extra = Some(s.clone());
                                i += 1;
                            }
                        }
                    }
                    let mut class = None;
                    if d == "Texture" {
                        class = Some(string(&mut i)?);
                    }
                    let p = params::parse(file, line, t, &mut i)?;
                    self.directive(&d, &kind, extra, class, p)?;
                }
            }
        }
        Ok(())
    }

    fn directive(
        &mut self,
        d: &str,
        kind: &str,
        extra: Option<String>,
        class: Option<String>,
        p: Params,
    ) -> Result<(), SceneError> {
        match d {
            "Camera" => {
                if !CAMERAS.contains(&kind) {
                    return Err(p.error(format!(
                        "unknown camera type \"{}\" (pbrt-v4 has {})",
                        clip(kind, 40),
                        CAMERAS.join(", ")
                    )));
                }
                if kind != "perspective" {
                    self.b.ignore_at(format!("Camera \"{kind}\" (rendered as perspective)"), at(&p.file, p.line));
                }
                let m = self.gs.ctm;
                if !m.is_finite() || glam::DMat3::from_mat4(m).determinant() == 0.0 {
                    return Err(p.error("the camera's transform is singular (determinant 0): it cannot be inverted"));
                }
                let fov = p.float("fov", 90.0)? as f64;
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(p.error(format!("Camera fov {fov} is outside (0, 180) degrees")));
                }
                self.camera = Some((self.gs.ctm, fov));
                let proper = glam::DMat3::from_mat4(self.gs.ctm).determinant() > 0.0;
                self.mirror = if proper { MIRROR_X } else { DMat4::IDENTITY };
            }
            "Film" => {
                if !FILMS.contains(&kind) {
                    return Err(p.error(format!(
                        "unknown film type \"{}\" (pbrt-v4 has {})",
                        clip(kind, 40),
                        FILMS.join(", ")
                    )));
                }
                let (w, h) = (p.int("xresolution", 1280)?, p.int("yresolution", 720)?);
                if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
                    return Err(p.error(format!("Film resolution {w}x{h} is out of range (1..=16384 per side)")));
                }
                self.film = [w as u32, h as u32];
                self.b.count("film size (the default image size)", 1);
                let (crop, warning) = film::pixel_bounds(&p, w as u32, h as u32)?;
                self.crop = crop;
                if let Some(w) = warning {
                    self.b.scene.warnings.push(format!("{}: line {}: {w}", p.file.display(), p.line));
                }
                if crop.is_some() {
                    self.b.count("film crop (the image is that part of the film)", 1);
                }
                p.has("filename");
            }
            "Texture" => self.texture(kind, extra.as_deref().unwrap_or(""), class.as_deref().unwrap_or(""), &p)?,
            "Material" => {
                let desc = self.material_desc(&format!("{}:{}", p.file.display(), p.line), kind, &p)?;
                self.gs.material = self.b.add_desc(desc);
            }
            "MakeNamedMaterial" => {
                let ty = p
                    .string("type")?
                    .ok_or_else(|| p.error(format!("MakeNamedMaterial \"{kind}\": no \"string type\"")))?;
                let desc = self.material_desc(kind, &ty, &p)?;
                let index = self.b.add_desc(desc);
                self.named_materials.insert(kind.to_string(), index);
            }
            "NamedMaterial" => {
                self.gs.material = *self.named_materials.get(kind).ok_or_else(|| {
                    p.error(format!("NamedMaterial \"{kind}\": no such material (MakeNamedMaterial)"))
                })?;
            }
            "AreaLightSource" => {
                if kind != "diffuse" {
                    self.b.ignore_at(format!("AreaLightSource \"{}\"", clip(kind, 40)), at(&p.file, p.line));
                } else {
                    let l = self.spectrum(&p, "L", Vec3::ONE)?;
                    let scale = lights::light_scale(&p)?;
                    let two_sided = p.bool("twosided", false)?;
                    if !(l * scale).is_finite() {
                        return Err(p.error("the area light's radiance × scale is out of the range of 32-bit floats"));
                    }
                    self.gs.area = Some(AreaLight { radiance: l * scale, two_sided });
                }
            }
            "LightSource" => self.light(kind, &p)?,
            "Shape" => {
                let call = ShapeCall {
                    kind: kind.into(),
                    params: Rc::new(p),
                    ctm: self.gs.ctm,
                    reverse: self.gs.reverse,
                    material: self.gs.material,
                    area: self.gs.area.clone(),
                };
                if let Some((_, shapes)) = &mut self.object {
                    shapes.push(call);
                } else {
                    self.shape(call)?;
                }
                return Ok(());
            }
            "Integrator" if INTEGRATORS_AS_PATHS.contains(&kind) => {
                // pbrt-v4's default maxdepth is 5 for every integrator that has one.
                let depth = p.int("maxdepth", 5)?;
                if !(1..=256).contains(&depth) {
                    return Err(p.error(format!("Integrator \"{kind}\": maxdepth {depth} is out of range (1..=256)")));
                }
                let at = at(&p.file, p.line);
                if !matches!(kind, "path" | "volpath") {
                    self.b.warnings.push(format!(
                        "Integrator \"{kind}\" (at {at}) is rendered as path tracing with the same maxdepth, the nearest \
                         estimator mislab has"
                    ));
                }
                self.b.scene.file_settings.max_depth = Some((depth as u32, format!("Integrator \"{kind}\" at {at}")));
            }
            "Sampler" => {
                let spp = match kind {
                    "stratified" => p.int("xsamples", 4)? * p.int("ysamples", 4)?,
                    _ => p.int("pixelsamples", 16)?,
                };
                if !(1..=1 << 24).contains(&spp) {
                    return Err(p.error(format!("Sampler \"{kind}\": {spp} samples per pixel is out of range")));
                }
                p.has("jitter");
                p.has("seed");
                p.has("randomization");
                let at = at(&p.file, p.line);
                let source = format!("Sampler \"{kind}\" at {at}");
                // pbrt-v4's samplers, each as the nearest mislab has ((0,2)-sequences as Sobol).
                let sampler = match kind {
                    "independent" => Some("independent"),
                    "stratified" => Some("stratified"),
                    "halton" => Some("halton"),
                    "sobol" | "paddedsobol" | "zsobol" | "pmj02bn" => Some("sobol"),
                    _ => None,
                };
                self.b.scene.file_settings.sampler = sampler.map(|s| (s, source.clone()));
                self.b.scene.file_settings.spp = Some((spp as u32, source));
            }
            "PixelFilter" => {
                // pbrt-v4's defaults: box 0.5, triangle 2, gaussian 1.5 (σ 0.5), mitchell 2, sinc 4.
                let (shape, default_radius) = match kind {
                    "box" => ("box", 0.5),
                    "triangle" => ("triangle", 2.0),
                    "gaussian" => ("gaussian", 1.5),
                    "mitchell" => ("gaussian", 2.0),
                    "sinc" => ("gaussian", 4.0),
                    other => return Err(p.error(format!("unknown PixelFilter \"{}\"", clip(other, 40)))),
                };
                let (rx, ry) = (p.float("xradius", default_radius)?, p.float("yradius", default_radius)?);
                let sigma = p.float("sigma", 0.5)?;
                for (name, v) in [("xradius", rx), ("yradius", ry), ("sigma", sigma)] {
                    if !(v.is_finite() && (0.05..=16.0).contains(&v)) {
                        return Err(p.error(format!("PixelFilter \"{kind}\": {name} {v} is out of range (0.05 to 16)")));
                    }
                }
                let at = at(&p.file, p.line);
                if rx != ry {
                    self.b.warnings.push(format!(
                        "PixelFilter \"{kind}\" (at {at}): xradius {rx} and yradius {ry} differ; mislab's filters have \
                         one radius, {} is used",
                        rx.max(ry)
                    ));
                }
                if shape != kind {
                    self.b.warnings.push(format!(
                        "PixelFilter \"{kind}\" (at {at}) is rendered with a gaussian filter of the same radius, the \
                         nearest mislab has (it has no negative lobes)"
                    ));
                    p.has("B");
                    p.has("C");
                    p.has("tau");
                }
                let filter = FileFilter { shape, radius: rx.max(ry), sigma };
                self.b.scene.file_settings.filter = Some((filter, format!("PixelFilter \"{kind}\" at {at}")));
            }
            "Integrator" | "Accelerator" | "ColorSpace" | "Option" | "MakeNamedMedium" | "MediumInterface"
            | "Attribute" | "CoordinateSystem" | "CoordSysTransform" | "TransformTimes" | "ActiveTransform" => {
                let what = if kind.is_empty() { d.to_string() } else { format!("{d} \"{kind}\"") };
                self.b.ignore(what);
                for u in p.unused() {
                    p.has(u.trim_matches('"').split(' ').nth(1).unwrap_or(""));
                }
                return Ok(());
            }
            _ => return Err(p.error(format!("unknown directive '{}'", clip(d, 40)))),
        }
        for u in p.unused() {
            self.b.ignore(format!("{d} \"{kind}\" parameter {u}"));
        }
        Ok(())
    }
}

/// pbrt's LookAt (camera-from-world): x = up × dir, y = dir × x, z = dir.
fn look_at(v: &[f64]) -> Option<DMat4> {
    let (eye, target, up) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]), DVec3::new(v[6], v[7], v[8]));
    let dir = (target - eye).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
    Some(world_from_camera.inverse())
}
