//! What the pbrt and Mitsuba importers share once a file is parsed: materials from their descriptions (one mislab
//! material per description and emission), meshes moved to world space with pbrt's / Mitsuba's orientation rules,
//! and the lists of what was imported and what was ignored.

use super::import_material::{self, Mapped, MaterialDesc};
use super::import_texture::TextureCache;
use super::{Mesh, Scene, SceneError, Sphere};
use crate::io::input_file::clip;
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::collections::{BTreeMap, HashMap};

/// Accumulates an imported scene.
#[derive(Default)]
pub struct Builder {
    /// The scene so far.
    pub scene: Scene,
    /// Material descriptions, indexed by shapes.
    pub descs: Vec<MaterialDesc>,
    mapped: HashMap<(usize, [u32; 3], bool), Option<u32>>,
    textures: TextureCache,
    /// Cut-out masks by file, and materials with a mask: (material, mask) → the masked copy.
    masks: HashMap<std::path::PathBuf, u32>,
    masked: HashMap<(u32, u32), u32>,
    /// Approximation warnings (one per material).
    pub warnings: Vec<String>,
    /// Ignored features: what → how often.
    pub ignored: BTreeMap<String, usize>,
    /// Where each ignored feature that has a place was first met (`scene.pbrt: line 12`).
    pub ignored_at: BTreeMap<String, String>,
    /// Imported things: what → how many.
    pub imported: BTreeMap<String, usize>,
    /// Shapes left out because their material is invisible.
    pub invisible_shapes: usize,
}

/// A mesh in object space, ready to be placed.
pub struct ObjectMesh {
    /// Name, for messages.
    pub name: String,
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Normals (empty: the geometric ones, flat).
    pub normals: Vec<Vec3>,
    /// UVs in the file's convention (v up); empty if none.
    pub uvs: Vec<Vec2>,
    /// Triangles (indices checked by the caller).
    pub indices: Vec<[u32; 3]>,
}

impl Builder {
    /// Notes one ignored feature.
    pub fn ignore(&mut self, what: impl Into<String>) {
        *self.ignored.entry(what.into()).or_default() += 1;
    }
    /// Notes one ignored feature met at `at` (`scene.pbrt: line 12`); the warning and the import report name the
    /// first place.
    pub fn ignore_at(&mut self, what: impl Into<String>, at: String) {
        let what = what.into();
        self.ignored_at.entry(what.clone()).or_insert(at);
        self.ignore(what);
    }
    /// Counts one imported thing.
    pub fn count(&mut self, what: &str, n: usize) {
        *self.imported.entry(what.into()).or_default() += n;
    }
    /// Adds a material description; returns its index.
    pub fn add_desc(&mut self, desc: MaterialDesc) -> usize {
        self.descs.push(desc);
        self.descs.len() - 1
    }
    /// The scene material for description `desc` emitting `emission`, from both faces when `two_sided` (None:
    /// leave the shape out).
    pub fn material(&mut self, desc: usize, emission: Vec3, two_sided: bool) -> Result<Option<u32>, SceneError> {
        let key = (desc, emission.to_array().map(f32::to_bits), two_sided);
        if let Some(m) = self.mapped.get(&key) {
            return Ok(*m);
        }
        let mut warnings = Vec::new();
        let first = !self.mapped.keys().any(|k| k.0 == desc);
        let m = match import_material::map(&self.descs[desc], &mut self.scene, &mut self.textures, &mut warnings)? {
            // An emitter behind glass still emits: keep it, as a black emitter.
            Mapped::Invisible if emission.max_element() > 0.0 => {
                let mut m = super::Material::emitter(&self.descs[desc].name, emission);
                m.name = format!("{} (emitter)", self.descs[desc].name);
                m.emission_two_sided = two_sided;
                self.scene.materials.push(m);
                Some(self.scene.materials.len() as u32 - 1)
            }
            Mapped::Invisible => None,
            Mapped::Material(mut m) => {
                m.emission = emission;
                m.emission_two_sided = two_sided && emission.max_element() > 0.0;
                self.scene.materials.push(*m);
                Some(self.scene.materials.len() as u32 - 1)
            }
        };
        if first {
            self.warnings.extend(warnings);
        }
        self.mapped.insert(key, m);
        Ok(m)
    }

    /// The cut-out mask of image `file` (a texture whose alpha channel is the coverage, shaders/alpha.wgsl): the
    /// image's alpha channel where it has one that is not all opaque, else its first channel (pbrt-v4's float
    /// texel). A leaf texture with transparent surroundings cuts them out either way.
    /// `referenced_by` (`scene.pbrt: line 12`) is named in errors about the image.
    pub fn alpha_mask(&mut self, file: &std::path::Path, referenced_by: &str) -> Result<u32, SceneError> {
        if let Some(&t) = self.masks.get(file) {
            return Ok(t);
        }
        let (width, height, mut texels) = super::import_texture::load_rgba8(file, false, referenced_by)?;
        if texels.iter().all(|c| c[3] == 255) {
            for c in &mut texels {
                c[3] = c[0];
            }
        }
        self.scene.textures.push(super::Texture {
            name: format!("{} (alpha mask)", file.display()),
            width,
            height,
            texels,
            srgb: false,
            wrap_s: super::Wrap::Repeat,
            wrap_t: super::Wrap::Repeat,
            nearest: false,
            kind: super::TextureKind::Image,
        });
        let t = self.scene.textures.len() as u32 - 1;
        self.masks.insert(file.to_path_buf(), t);
        self.count("alpha cut-out masks", 1);
        Ok(t)
    }

    /// Scene material `material` with cut-out mask `mask` (a copy per pair).
    pub fn masked_material(&mut self, material: u32, mask: u32) -> u32 {
        if let Some(&m) = self.masked.get(&(material, mask)) {
            return m;
        }
        let mut m = self.scene.materials[material as usize].clone();
        m.alpha_texture = Some(mask);
        m.name = format!("{} (cut-out)", m.name);
        self.scene.materials.push(m);
        let i = self.scene.materials.len() as u32 - 1;
        self.masked.insert((material, mask), i);
        i
    }

    /// Places `mesh` with `to_world`. Triangles face their vertex normals when there are any; otherwise they
    /// are flipped when `flip` (pbrt: ReverseOrientation xor a handedness-swapping transform) and get flat normals.
    /// A position or uv that is not a finite 32-bit float (in the file, or once transformed) is an error: the
    /// problem alone, which the caller places in its file.
    pub fn add_mesh(&mut self, mesh: ObjectMesh, to_world: Mat4, flip: bool, material: u32) -> Result<(), String> {
        if !to_world.is_finite() {
            return Err("the shape's transform is out of the range of 32-bit floats".into());
        }
        if Mat3::from_mat4(to_world).determinant() == 0.0 {
            return Err("the shape's transform is singular (its 3×3 part has determinant 0)".into());
        }
        if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} of '{}' is not a finite 32-bit float", clip(&mesh.name, 80)));
        }
        if let Some(i) = mesh.uvs.iter().position(|t| !t.is_finite()) {
            return Err(format!("texture coordinate {i} of '{}' is not a finite 32-bit float", clip(&mesh.name, 80)));
        }
        let normal_m = Mat3::from_mat4(to_world).inverse().transpose();
        let p: Vec<Vec3> = mesh.positions.iter().map(|&p| to_world.transform_point3(p)).collect();
        if let Some(i) = p.iter().position(|p| !p.is_finite()) {
            return Err(format!(
                "vertex {i} of '{}' is out of the range of 32-bit floats once transformed",
                clip(&mesh.name, 80)
            ));
        }
        let n: Vec<Vec3> = mesh.normals.iter().map(|&n| (normal_m * n).normalize_or(Vec3::Y)).collect();
        // Our textures are top row first (v down); pbrt and Mitsuba put v = 0 at the bottom.
        let uv: Vec<Vec2> = mesh.uvs.iter().map(|&t| Vec2::new(t.x, 1.0 - t.y)).collect();
        let mut out = Mesh { name: mesh.name, material, ..Default::default() };
        let has_n = n.len() == p.len() && !p.is_empty();
        let has_uv = uv.len() == p.len();
        if has_n {
            out.positions = p;
            out.normals = n;
            out.uvs = if has_uv { uv } else { vec![] };
            out.indices = mesh
                .indices
                .iter()
                .map(|&[a, b, c]| {
                    let (pa, pb, pc) =
                        (out.positions[a as usize], out.positions[b as usize], out.positions[c as usize]);
                    let ng = (pb - pa).cross(pc - pa);
                    let ns = out.normals[a as usize] + out.normals[b as usize] + out.normals[c as usize];
                    if ng.dot(ns) < 0.0 {
                        [a, c, b]
                    } else {
                        [a, b, c]
                    }
                })
                .collect();
        } else {
            // Flat: each triangle gets its own three vertices with the face normal.
            for &[a, b, c] in &mesh.indices {
                let [a, b, c] = if flip { [a, c, b] } else { [a, b, c] };
                let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
                let ng = (pb - pa).cross(pc - pa).normalize_or(Vec3::Y);
                let base = out.positions.len() as u32;
                for i in [a, b, c] {
                    out.positions.push(p[i as usize]);
                    out.normals.push(ng);
                    if has_uv {
                        out.uvs.push(uv[i as usize]);
                    }
                }
                out.indices.push([base, base + 1, base + 2]);
            }
        }
        self.count("triangles", out.indices.len());
        self.scene.meshes.push(out);
        Ok(())
    }

    /// Places a sphere of `radius` at the origin of `to_world` (uniform scale assumed; the mean is used). A
    /// singular transform or a centre or radius out of the range of 32-bit floats is an error (the problem alone).
    pub fn add_sphere(&mut self, to_world: Mat4, radius: f32, material: u32) -> Result<(), String> {
        let center = to_world.transform_point3(Vec3::ZERO);
        let scale = Mat3::from_mat4(to_world).determinant().abs().cbrt();
        let radius = radius * scale;
        if !to_world.is_finite() || !(radius > 0.0 && radius.is_finite()) || !center.is_finite() {
            return Err(format!(
                "the sphere's transform is singular, or its centre or radius ({radius}) is out of the range of 32-bit \
                 floats"
            ));
        }
        self.scene.spheres.push(Sphere { center, radius, material });
        self.count("spheres", 1);
        Ok(())
    }

    /// Ends the import: the ignored list becomes one warning, and the import report is filled in.
    pub fn finish(mut self, format: &str) -> Scene {
        self.scene.warnings.append(&mut self.warnings);
        if self.invisible_shapes > 0 {
            self.scene.warnings.push(format!(
                "{} shapes with see-through materials (interface, null) were left out",
                self.invisible_shapes
            ));
        }
        let placed = |k: &String| match self.ignored_at.get(k) {
            Some(at) => format!("{k} (at {at})"),
            None => k.clone(),
        };
        if !self.ignored.is_empty() {
            let list: Vec<String> = self
                .ignored
                .iter()
                .map(|(k, n)| if *n > 1 { format!("{} (×{n}, first)", placed(k)) } else { placed(k) })
                .collect();
            self.scene.warnings.push(format!("{format}: ignored (not supported by mislab): {}", list.join("; ")));
        }
        let mut report = vec![format!("imported from {format}:")];
        report.extend(self.imported.iter().map(|(k, n)| format!("  {n} {k}")));
        // The materials some shape uses (a file's unused declarations and the format's unused defaults are not
        // imported).
        let used: std::collections::BTreeSet<usize> = self.mapped.keys().map(|k| k.0).collect();
        report.push(format!("  {} materials used: {}", used.len(), {
            let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
            for &d in &used {
                *kinds.entry(self.descs[d].kind.as_str()).or_default() += 1;
            }
            kinds.iter().map(|(k, n)| format!("{n} {k}")).collect::<Vec<_>>().join(", ")
        }));
        if self.ignored.is_empty() {
            report.push("ignored: nothing".into());
        } else {
            report.push("ignored:".into());
            report.extend(self.ignored.iter().map(|(k, n)| format!("  {} ×{n}", placed(k))));
        }
        self.scene.import_report = report;
        self.scene
    }
}

/// Segments of a disk's triangle fan.
const DISK_SEGMENTS: usize = 64;

/// A disk at z = `height` facing +z (−z when `reverse`), as a fan whose area is the disk's.
pub fn disk(radius: f32, height: f32, reverse: bool) -> ObjectMesh {
    let n = DISK_SEGMENTS as f32;
    let tau = 2.0 * std::f32::consts::PI;
    // A regular n-gon of circumradius r has area n r² sin(2π/n) / 2: scale r so it equals π r².
    let r = radius * (tau / (n * (tau / n).sin())).sqrt();
    let mut positions = vec![Vec3::new(0.0, 0.0, height)];
    let mut uvs = vec![Vec2::ZERO];
    for i in 0..DISK_SEGMENTS {
        let phi = tau * i as f32 / n;
        positions.push(Vec3::new(r * phi.cos(), r * phi.sin(), height));
        uvs.push(Vec2::new(i as f32 / n, 1.0));
    }
    let normal = if reverse { Vec3::NEG_Z } else { Vec3::Z };
    let normals = vec![normal; positions.len()];
    let k = DISK_SEGMENTS as u32;
    let indices = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
    ObjectMesh { name: "disk".into(), positions, normals, uvs, indices }
}

/// Mitsuba's `rectangle`: [−1, 1]² at z = 0 facing +z.
pub fn rectangle() -> ObjectMesh {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uvs = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
    ObjectMesh {
        name: "rectangle".into(),
        positions,
        normals: vec![Vec3::Z; 4],
        uvs,
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Mitsuba's `cube`: [−1, 1]³ with outward faces.
pub fn cube() -> ObjectMesh {
    let mut m = ObjectMesh { name: "cube".into(), positions: vec![], normals: vec![], uvs: vec![], indices: vec![] };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (u, v) = (n.any_orthonormal_pair().0, n.any_orthonormal_pair().1);
            let base = m.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.positions.push(n + u * a + v * b);
                m.normals.push(n);
                m.uvs.push(Vec2::new((a + 1.0) / 2.0, (b + 1.0) / 2.0));
            }
            m.indices.push([base, base + 1, base + 2]);
            m.indices.push([base, base + 2, base + 3]);
        }
    }
    m
}
