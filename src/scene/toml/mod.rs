//! mislab's small TOML scene format (documented in `docs/scene-format.md`): camera, named materials, analytic shapes,
//! inline meshes, punctual lights, an environment, and transformed glTF includes.

use super::envmap::load_envmap;
use super::{
    builtin::vertex_normals, Camera, Environment, LoadOptions, Material, MaterialKind, Mesh, PunctualLight, Quad,
    Scene, SceneError, Sphere,
};
use ::toml::Spanned;
use glam::{Mat3, Mat4, Quat, Vec3};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod material;
use material::{material, MaterialDef};

/// Loads a TOML scene. Relative paths inside it (environment maps, includes) are resolved against its directory.
/// Errors name the file and, where the problem is in the file, its line.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let text = crate::io::input_file::read_bounded_text(path, crate::io::input_file::MAX_TOML_BYTES)
        .map_err(|m| SceneError::new(path, m.to_string()))?;
    let ctx = Ctx { path, text: &text, dir: path.parent().unwrap_or(Path::new("")).to_path_buf() };
    let file: FileDef = ::toml::from_str(&text).map_err(|e| {
        let at = e.span().map(|s| ctx.position(s.start)).unwrap_or_default();
        // toml's messages can span lines ("invalid table header\nexpected `.`, `]`"); keep ours on one.
        let message = crate::io::input_file::clip_quoted(&e.message().trim_end().replace('\n', "; "), 80);
        SceneError::new(path, format!("{at}{message}"))
    })?;
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
    build(&ctx, file, name, options)
}

/// The file being loaded, for resolving paths and turning byte offsets into line numbers.
struct Ctx<'a> {
    path: &'a Path,
    text: &'a str,
    dir: PathBuf,
}

impl Ctx<'_> {
    /// "line L, column C: " for a byte offset.
    fn position(&self, offset: usize) -> String {
        let before = &self.text[..offset.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let column = before.chars().rev().take_while(|&c| c != '\n').count() + 1;
        format!("line {line}, column {column}: ")
    }
    /// An error about the item that `span` covers.
    fn err<T>(&self, span: &Spanned<T>, message: impl AsRef<str>) -> SceneError {
        let line = self.text[..span.span().start.min(self.text.len())].matches('\n').count() + 1;
        SceneError::new(self.path, format!("line {line}: {}", message.as_ref()))
    }
    fn resolve(&self, p: &str) -> PathBuf {
        // `join` keeps absolute paths as they are.
        self.dir.join(p)
    }
}

// ---------------------------------------------------------------------------------------------------------------
// The file's shape. Every table denies unknown keys so that typos are errors, not silently ignored settings.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDef {
    camera: Option<Spanned<CameraDef>>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialDef>>,
    #[serde(default)]
    sphere: Vec<Spanned<SphereDef>>,
    #[serde(default)]
    quad: Vec<Spanned<QuadDef>>,
    #[serde(default)]
    rectangle: Vec<Spanned<RectangleDef>>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshDef>>,
    #[serde(default)]
    light: Vec<Spanned<LightDef>>,
    environment: Option<Spanned<EnvironmentDef>>,
    #[serde(default)]
    include: Vec<Spanned<IncludeDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    position: V3,
    look_at: Option<V3>,
    forward: Option<V3>,
    up: Option<V3>,
    vfov: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereDef {
    center: V3,
    radius: f32,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct QuadDef {
    corner: V3,
    edge_u: V3,
    edge_v: V3,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RectangleDef {
    center: V3,
    normal: V3,
    size: Splat<2>,
    u_axis: Option<V3>,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDef {
    name: Option<String>,
    positions: Vec<V3>,
    indices: Vec<Arr<u32, 3>>,
    normals: Option<Vec<V3>>,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDef {
    #[serde(rename = "type")]
    kind: String,
    position: Option<V3>,
    direction: Option<V3>,
    intensity: Option<Splat<3>>,
    irradiance: Option<Splat<3>>,
    inner_cone: Option<f32>,
    outer_cone: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentDef {
    constant: Option<Splat<3>>,
    map: Option<String>,
    scale: Option<f32>,
    rotation: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct IncludeDef {
    gltf: String,
    translate: Option<V3>,
    rotate: Option<RotateDef>,
    scale: Option<Splat<3>>,
    scene: Option<usize>,
    use_camera: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateDef {
    axis: Option<V3>,
    angle: Option<f32>,
    euler: Option<V3>,
}

/// A point or vector: exactly three numbers.
type V3 = Arr<f32, 3>;

/// An array of exactly N values. (The toml deserializer does not reject extra elements for Rust's fixed-size
/// arrays: with `[f32; 3]`, `position = [0, 1, 5, 2]` would load as `[0, 1, 5]` without a word.)
#[derive(Clone, Copy)]
struct Arr<T, const N: usize>([T; N]);

impl<T, const N: usize> From<Arr<T, N>> for [T; N] {
    fn from(a: Arr<T, N>) -> [T; N] {
        a.0
    }
}

impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Deserialize<'de> for Arr<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Arr<T, N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an array of {N} numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [T::default(); N];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                let mut extra = 0;
                while seq.next_element::<de::IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(de::Error::invalid_length(N + extra, &self));
                }
                Ok(Arr(out))
            }
        }
        d.deserialize_seq(V::<T, N>(std::marker::PhantomData))
    }
}

/// A number (repeated N times) or an array of N numbers: `0.5` or `[0.5, 0.4, 0.3]`.
#[derive(Clone, Copy)]
struct Splat<const N: usize>([f32; N]);

impl<'de, const N: usize> Deserialize<'de> for Splat<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> Visitor<'de> for V<N> {
            type Value = Splat<N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "a number or an array of {N} numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(Splat([v as f32; N]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(Splat([v as f32; N]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(Splat([v as f32; N]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = [0.0; N];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq.next_element::<f32>()?.ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(N + 1, &self));
                }
                Ok(Splat(out))
            }
        }
        d.deserialize_any(V::<N>)
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Building the scene.

fn build(ctx: &Ctx, file: FileDef, name: String, options: &LoadOptions) -> Result<Scene, SceneError> {
    let mut scene = Scene { name, ..Default::default() };

    if let Some(c) = &file.camera {
        scene.camera = camera(ctx, c)?;
    }

    // Materials get indices in name order (the TOML table has no meaningful order).
    let mut material_index = BTreeMap::new();
    for (name, def) in &file.materials {
        let m = material(ctx, name, def, &mut scene.warnings)?;
        material_index.insert(name.as_str(), scene.materials.len() as u32);
        scene.materials.push(m);
    }
    let lookup = |span: &dyn Fn(&str) -> SceneError, name: &str| -> Result<u32, SceneError> {
        material_index.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = material_index.keys().copied().collect();
            let known = if known.is_empty() {
                "none are defined".to_string()
            } else {
                format!("defined: {}", known.join(", "))
            };
            span(&format!("unknown material '{name}' ({known})"))
        })
    };

    for (i, s) in file.sphere.iter().enumerate() {
        let e = |m: &str| ctx.err(s, format!("[[sphere]] {}: {m}", i + 1));
        let d = s.get_ref();
        let center = finite_vec(d.center).ok_or_else(|| e("center must be finite"))?;
        if !(d.radius > 0.0 && d.radius.is_finite()) {
            return Err(e(&format!("radius must be positive and finite (got {})", d.radius)));
        }
        let material = lookup(&e, &d.material)?;
        scene.spheres.push(Sphere { center, radius: d.radius, material });
    }

    for (i, q) in file.quad.iter().enumerate() {
        let e = |m: &str| ctx.err(q, format!("[[quad]] {}: {m}", i + 1));
        let d = q.get_ref();
        let (corner, edge_u, edge_v) = match (finite_vec(d.corner), finite_vec(d.edge_u), finite_vec(d.edge_v)) {
            (Some(c), Some(u), Some(v)) => (c, u, v),
            _ => return Err(e("corner and edges must be finite")),
        };
        if edge_u.cross(edge_v).length_squared() <= 1e-20 {
            return Err(e("edge_u and edge_v are parallel or zero, so the quad has no area"));
        }
        let material = lookup(&e, &d.material)?;
        scene.quads.push(Quad { corner, edge_u, edge_v, material });
    }

    for (i, r) in file.rectangle.iter().enumerate() {
        let e = |m: &str| ctx.err(r, format!("[[rectangle]] {}: {m}", i + 1));
        let d = r.get_ref();
        let center = finite_vec(d.center).ok_or_else(|| e("center must be finite"))?;
        let normal = finite_vec(d.normal)
            .and_then(Vec3::try_normalize)
            .ok_or_else(|| e("normal must be a finite non-zero vector"))?;
        let [w, h] = d.size.0;
        if !(w > 0.0 && h > 0.0 && w.is_finite() && h.is_finite()) {
            return Err(e("size must be positive and finite"));
        }
        // The u axis defaults to +X projected into the plane (+Z when the normal is close to ±X).
        let hint = match d.u_axis {
            Some(a) => finite_vec(a).ok_or_else(|| e("u_axis must be finite"))?,
            None if normal.x.abs() < 0.9 => Vec3::X,
            None => Vec3::Z,
        };
        let tangent =
            (hint - normal * hint.dot(normal)).try_normalize().ok_or_else(|| e("u_axis is parallel to the normal"))?;
        // bitangent = normal × tangent makes tangent × bitangent = normal: the front faces along `normal`.
        let (edge_u, edge_v) = (tangent * w, normal.cross(tangent) * h);
        let material = lookup(&e, &d.material)?;
        scene.quads.push(Quad { corner: center - 0.5 * (edge_u + edge_v), edge_u, edge_v, material });
    }

    for (i, m) in file.mesh.iter().enumerate() {
        let e = |msg: &str| ctx.err(m, format!("[[mesh]] {}: {msg}", i + 1));
        let d = m.get_ref();
        let positions: Vec<Vec3> = d
            .positions
            .iter()
            .map(|p| finite_vec(*p))
            .collect::<Option<_>>()
            .ok_or_else(|| e("positions must be finite"))?;
        let indices: Vec<[u32; 3]> = d.indices.iter().map(|t| t.0).collect();
        if indices.is_empty() {
            return Err(e("no triangles (indices is empty)"));
        }
        if let Some(bad) = indices.iter().flatten().find(|&&i| i as usize >= positions.len()) {
            return Err(e(&format!("index {bad} is out of range ({} positions)", positions.len())));
        }
        let normals = match &d.normals {
            None => vertex_normals(&positions, &indices),
            Some(n) if n.len() != positions.len() => {
                return Err(e(&format!("{} normals for {} positions", n.len(), positions.len())));
            }
            Some(n) => n
                .iter()
                .map(|v| finite_vec(*v).and_then(Vec3::try_normalize))
                .collect::<Option<_>>()
                .ok_or_else(|| e("normals must be finite and non-zero"))?,
        };
        let material = lookup(&e, &d.material)?;
        let name = d.name.clone().unwrap_or_else(|| format!("mesh{}", i + 1));
        scene.meshes.push(Mesh { name, positions, normals, uvs: Vec::new(), indices, material });
    }

    for (i, l) in file.light.iter().enumerate() {
        scene.punctual_lights.push(light(ctx, i, l)?);
    }

    if let Some(env) = &file.environment {
        let (environment, warnings) = environment(ctx, env)?;
        scene.environment = environment;
        scene.warnings.extend(warnings);
    }

    for (i, inc) in file.include.iter().enumerate() {
        include(ctx, i, inc, options, &mut scene)?;
    }

    Ok(scene)
}

fn finite_vec(v: impl Into<[f32; 3]>) -> Option<Vec3> {
    let v = Vec3::from(v.into());
    v.is_finite().then_some(v)
}

fn camera(ctx: &Ctx, c: &Spanned<CameraDef>) -> Result<Camera, SceneError> {
    let e = |m: &str| ctx.err(c, format!("[camera]: {m}"));
    let d = c.get_ref();
    let position = finite_vec(d.position).ok_or_else(|| e("position must be finite"))?;
    let forward = match (d.look_at, d.forward) {
        (Some(_), Some(_)) => return Err(e("give either look_at or forward, not both")),
        (Some(t), None) => finite_vec(t).map(|t| t - position),
        (None, Some(f)) => finite_vec(f),
        (None, None) => Some(Vec3::NEG_Z),
    };
    let forward = forward
        .and_then(Vec3::try_normalize)
        .ok_or_else(|| e("the viewing direction is zero or not finite (look_at equals position?)"))?;
    let up = finite_vec(d.up.map_or([0.0, 1.0, 0.0], |u| u.0))
        .and_then(Vec3::try_normalize)
        .ok_or_else(|| e("up must be a finite non-zero vector"))?;
    if forward.cross(up).length_squared() < 1e-8 {
        return Err(e("up is parallel to the viewing direction"));
    }
    let vfov = d.vfov.unwrap_or(45.0);
    if !(vfov > 0.0 && vfov < 180.0) {
        return Err(e(&format!("vfov must be between 0 and 180 degrees (got {vfov})")));
    }
    Ok(Camera { position, forward, up, vfov: vfov.to_radians(), window: Camera::FULL_WINDOW })
}

fn light(ctx: &Ctx, i: usize, l: &Spanned<LightDef>) -> Result<PunctualLight, SceneError> {
    let d = l.get_ref();
    let e = |m: &str| ctx.err(l, format!("[[light]] {} (type \"{}\"): {m}", i + 1, d.kind));
    let given = [
        ("position", d.position.is_some()),
        ("direction", d.direction.is_some()),
        ("intensity", d.intensity.is_some()),
        ("irradiance", d.irradiance.is_some()),
        ("inner_cone", d.inner_cone.is_some()),
        ("outer_cone", d.outer_cone.is_some()),
    ];
    let allowed: &[&str] = match d.kind.as_str() {
        "point" => &["position", "intensity"],
        "spot" => &["position", "direction", "intensity", "inner_cone", "outer_cone"],
        "directional" => &["direction", "irradiance"],
        other => {
            return Err(ctx.err(
                l,
                format!("[[light]] {}: unknown type \"{other}\" (expected point, spot or directional)", i + 1),
            ));
        }
    };
    if let Some((key, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
        return Err(e(&format!("does not take '{key}' (it takes: {})", allowed.join(", "))));
    }
    let position = || d.position.and_then(finite_vec).ok_or_else(|| e("needs a finite 'position'"));
    let direction = || {
        d.direction
            .and_then(finite_vec)
            .and_then(Vec3::try_normalize)
            .ok_or_else(|| e("needs a finite non-zero 'direction'"))
    };
    let power = |key: &str, v: Option<Splat<3>>| -> Result<Vec3, SceneError> {
        let c = v.map(|s| Vec3::from(s.0)).ok_or_else(|| e(&format!("needs '{key}'")))?;
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(e(&format!("{key} must be finite and non-negative")));
        }
        Ok(c)
    };
    Ok(match d.kind.as_str() {
        "point" => PunctualLight::Point { position: position()?, intensity: power("intensity", d.intensity)? },
        "spot" => {
            // glTF's defaults: a hard-edged 45° cone.
            let (inner, outer) = (d.inner_cone.unwrap_or(0.0), d.outer_cone.unwrap_or(45.0));
            if !(0.0 <= inner && inner < outer && outer <= 90.0) {
                return Err(e(&format!("need 0 ≤ inner_cone < outer_cone ≤ 90 degrees (got {inner}, {outer})")));
            }
            PunctualLight::Spot {
                position: position()?,
                direction: direction()?,
                intensity: power("intensity", d.intensity)?,
                inner_cone: inner.to_radians(),
                outer_cone: outer.to_radians(),
            }
        }
        _ => PunctualLight::Directional { direction: direction()?, irradiance: power("irradiance", d.irradiance)? },
    })
}

fn environment(ctx: &Ctx, env: &Spanned<EnvironmentDef>) -> Result<(Environment, Vec<String>), SceneError> {
    let e = |m: &str| ctx.err(env, format!("[environment]: {m}"));
    let d = env.get_ref();
    match (&d.constant, &d.map) {
        (Some(_), Some(_)) => Err(e("give either constant or map, not both")),
        (Some(c), None) => {
            if d.scale.is_some() || d.rotation.is_some() {
                return Err(e("scale and rotation only apply to a map"));
            }
            let c = Vec3::from(c.0);
            if !c.is_finite() || c.min_element() < 0.0 {
                return Err(e("constant must be finite and non-negative"));
            }
            Ok((Environment::Constant(c), Vec::new()))
        }
        (None, Some(map)) => {
            let scale = d.scale.unwrap_or(1.0);
            if !(scale >= 0.0 && scale.is_finite()) {
                return Err(e(&format!("scale must be finite and non-negative (got {scale})")));
            }
            let rotation = d.rotation.unwrap_or(0.0);
            if !rotation.is_finite() {
                return Err(e("rotation must be finite"));
            }
            let (map, warnings) = load_envmap(&ctx.resolve(map)).map_err(|err| e(&format!("map: {err}")))?;
            Ok((Environment::Map { map: Arc::new(map), scale, rotation: rotation.to_radians() }, warnings))
        }
        (None, None) => Err(e("needs constant = [r, g, b] or map = \"file.hdr\"")),
    }
}

/// Loads a glTF include, transforms it into place and merges it into `scene`.
fn include(
    ctx: &Ctx,
    i: usize,
    inc: &Spanned<IncludeDef>,
    options: &LoadOptions,
    scene: &mut Scene,
) -> Result<(), SceneError> {
    let d = inc.get_ref();
    let e = |m: &str| ctx.err(inc, format!("[[include]] {} ('{}'): {m}", i + 1, d.gltf));

    // Transform: scale, then rotate, then translate.
    let translate = finite_vec(d.translate.map_or([0.0; 3], |t| t.0)).ok_or_else(|| e("translate must be finite"))?;
    let scale = Vec3::from(d.scale.map(|s| s.0).unwrap_or([1.0; 3]));
    if !scale.is_finite() || scale.abs().min_element() < 1e-12 {
        return Err(e("scale must be finite and non-zero (a negative value mirrors)"));
    }
    let rotation = match &d.rotate {
        None => Quat::IDENTITY,
        Some(RotateDef { axis: Some(axis), angle: Some(angle), euler: None }) => {
            let axis = finite_vec(*axis)
                .and_then(Vec3::try_normalize)
                .ok_or_else(|| e("rotate.axis must be a finite non-zero vector"))?;
            if !angle.is_finite() {
                return Err(e("rotate.angle must be finite"));
            }
            Quat::from_axis_angle(axis, angle.to_radians())
        }
        Some(RotateDef { axis: None, angle: None, euler: Some(xyz) }) => {
            let [x, y, z] =
                finite_vec(*xyz).ok_or_else(|| e("rotate.euler must be finite"))?.to_array().map(f32::to_radians);
            // About the fixed world axes, X first, then Y, then Z.
            Quat::from_rotation_z(z) * Quat::from_rotation_y(y) * Quat::from_rotation_x(x)
        }
        Some(_) => {
            return Err(e(
                "rotate needs either { axis = [x, y, z], angle = degrees } or { euler = [x, y, z] } (degrees)",
            ))
        }
    };
    let matrix = Mat4::from_scale_rotation_translation(scale, rotation, translate);

    let path = ctx.resolve(&d.gltf);
    // The same check every input gets (a FIFO, a directory or /dev/zero is named as what it is).
    if let Err(m) = crate::io::input_file::check_readable(&path) {
        let m = match m {
            crate::io::input_file::InputError::NotFound => "not found".to_string(),
            m => m.to_string(),
        };
        return Err(e(&format!("glTF file {}: {m}", path.display())));
    }
    // The include's own `scene` (not the command line's --gltf-scene, which is for a top-level glTF file).
    let mut options = options.clone();
    options.gltf_scene = d.scene;
    // Contain loader panics here too, so the message says which include broke.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| super::gltf::load(&path, &options)))
        .map_err(|_| e("the glTF loader failed on this file (malformed?)"))?
        // The loader's error already names the glTF file.
        .map_err(|err| ctx.err(inc, format!("[[include]] {}: {err}", i + 1)))?;
    let mut loaded = loaded;
    transform_scene(&mut loaded, matrix).map_err(|m| e(&m))?;
    merge(scene, loaded, d.use_camera.unwrap_or(false));
    Ok(())
}

/// Applies an affine transform to everything positioned in `scene`. A mirroring transform (negative determinant)
/// reverses triangle winding and swaps quad edges so that fronts stay on the same physical side.
fn transform_scene(scene: &mut Scene, m: Mat4) -> Result<(), String> {
    let linear = Mat3::from_mat4(m);
    let normal_matrix = linear.inverse().transpose();
    let mirrored = linear.determinant() < 0.0;
    for mesh in &mut scene.meshes {
        for p in &mut mesh.positions {
            *p = m.transform_point3(*p);
        }
        for n in &mut mesh.normals {
            *n = (normal_matrix * *n).try_normalize().unwrap_or(Vec3::Y);
        }
        if mirrored {
            for t in &mut mesh.indices {
                t.swap(1, 2);
            }
        }
    }
    if !scene.spheres.is_empty() {
        let s = Vec3::new(linear.x_axis.length(), linear.y_axis.length(), linear.z_axis.length());
        if (s.max_element() - s.min_element()) > 1e-5 * s.max_element() {
            return Err("cannot scale analytic spheres non-uniformly".into());
        }
        for sphere in &mut scene.spheres {
            sphere.center = m.transform_point3(sphere.center);
            sphere.radius *= s.x;
        }
    }
    for q in &mut scene.quads {
        q.corner = m.transform_point3(q.corner);
        q.edge_u = linear * q.edge_u;
        q.edge_v = linear * q.edge_v;
        if mirrored {
            std::mem::swap(&mut q.edge_u, &mut q.edge_v);
        }
    }
    // Directions are tangent vectors: they transform with the linear part (then renormalise).
    let dir = |d: Vec3| (linear * d).try_normalize().unwrap_or(d);
    for l in &mut scene.punctual_lights {
        match l {
            PunctualLight::Point { position, .. } => *position = m.transform_point3(*position),
            PunctualLight::Spot { position, direction, .. } => {
                *position = m.transform_point3(*position);
                *direction = dir(*direction);
            }
            PunctualLight::Directional { direction, .. } => *direction = dir(*direction),
        }
    }
    let c = &mut scene.camera;
    c.position = m.transform_point3(c.position);
    c.forward = dir(c.forward);
    c.up = dir(c.up);
    Ok(())
}

/// Appends `other` to `scene`, re-indexing materials and textures.
fn merge(scene: &mut Scene, other: Scene, use_camera: bool) {
    let material_offset = scene.materials.len() as u32;
    let texture_offset = scene.textures.len() as u32;
    for mut m in other.materials {
        for t in [&mut m.base_color_texture, &mut m.metallic_roughness_texture, &mut m.emissive_texture]
            .into_iter()
            .flatten()
        {
            t.texture += texture_offset;
        }
        scene.materials.push(m);
    }
    scene.textures.extend(other.textures);
    scene.meshes.extend(other.meshes.into_iter().map(|mut m| {
        m.material += material_offset;
        m
    }));
    scene.spheres.extend(other.spheres.into_iter().map(|mut s| {
        s.material += material_offset;
        s
    }));
    scene.quads.extend(other.quads.into_iter().map(|mut q| {
        q.material += material_offset;
        q
    }));
    scene.punctual_lights.extend(other.punctual_lights);
    if matches!(scene.environment, Environment::None) {
        scene.environment = other.environment;
    }
    if use_camera {
        scene.camera = other.camera;
    }
    scene.warnings.extend(other.warnings);
}
