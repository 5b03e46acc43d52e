//! Meshes and primitives: reading a primitive's attributes and indices, assembling triangles from lists, strips
//! and fans, and building the world-space mesh (winding fixed for mirrors, non-finite triangles dropped,
//! normals repaired, unused vertices compacted).

use super::accessor::{same_count, to_f32, Usage};
use super::notes::Notes;
use super::{json, Loader, Res};
use crate::scene::Mesh;
use glam::{Mat3, Mat4, Vec2, Vec3};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

/// One primitive's vertex data in its mesh's local space.
struct Geometry {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

impl Loader<'_> {
    pub(super) fn place_mesh(&mut self, mesh_index: usize, world: &Mat4) -> Res<()> {
        let root = self.root;
        let count = root.meshes.len();
        let mesh = root
            .meshes
            .get(mesh_index)
            .ok_or_else(|| format!("mesh {mesh_index} does not exist (the file has {count} meshes)"))?;
        let name = mesh.name.clone().unwrap_or_else(|| format!("mesh {mesh_index}"));
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh '{name}' primitive {p}");
            if let Some(built) = self.primitive(primitive, &name, &what, world)? {
                self.scene.meshes.push(built);
            }
        }
        Ok(())
    }

    /// One primitive instance as a world-space mesh; None when it has nothing to render.
    fn primitive(&mut self, prim: &json::mesh::Primitive, name: &str, what: &str, world: &Mat4) -> Res<Option<Mesh>> {
        let Checked::Valid(mode) = prim.mode else { return Err(format!("{what}: invalid primitive mode")) };
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.notes.skipped_primitives += 1;
            return Ok(None);
        }
        if prim.targets.as_ref().is_some_and(|t| !t.is_empty()) {
            self.notes.once("morph", || "morph targets are ignored: meshes are rendered in their base shape".into());
        }
        let Some(geometry) = self.geometry(prim, what)? else { return Ok(None) };
        let (triangles, leftover) = assemble(mode, &geometry.indices);
        if leftover > 0 {
            self.notes.push(format!("{what}: {leftover} trailing index(es) do not form a triangle and were ignored"));
        }
        let material = self.material(prim.material.map(|m| m.value()))?;
        let m = &self.scene.materials[material as usize];
        let textured =
            m.base_color_texture.is_some() || m.metallic_roughness_texture.is_some() || m.emissive_texture.is_some();
        if textured && geometry.uvs.is_empty() {
            self.notes
                .push(format!("{what} has a textured material but no TEXCOORD_0; its textures are sampled at (0, 0)"));
        }
        // A NaN or Inf position is corrupt data, not something to guess around: refuse the file, naming the vertex.
        let used = triangles.iter().flatten().map(|&i| (i, world.transform_point3(geometry.positions[i as usize])));
        let bad: Vec<(u32, Vec3)> = used.filter(|(_, p)| !p.is_finite()).collect();
        if let Some(&(i, p)) = bad.first() {
            let file_value = geometry.positions[i as usize];
            let (source, p) = if file_value.is_finite() {
                ("its node transform makes it non-finite", p)
            } else {
                ("POSITION holds NaN/Inf", file_value)
            };
            return Err(format!(
                "{what}: non-finite vertex position: vertex {i} is ({}, {}, {}) ({source}; {} use(s) by triangles in all)",
                p.x,
                p.y,
                p.z,
                bad.len()
            ));
        }
        let mesh = Mesh { name: name.to_string(), material, ..Default::default() };
        Ok(build_mesh(mesh, geometry, triangles, world, &mut self.notes))
    }

    /// Reads and cross-checks a primitive's attributes and indices.
    fn geometry(&mut self, prim: &json::mesh::Primitive, what: &str) -> Res<Option<Geometry>> {
        let attribute = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let Some(position) = attribute(Semantic::Positions) else {
            self.notes.push(format!("{what} has no POSITION attribute and was skipped"));
            return Ok(None);
        };
        // An accessor with neither a bufferView nor sparse values is all zeros (spec): zero positions, or indices
        // that are all 0, make every triangle degenerate. Skip it before allocating: a few bytes of JSON can
        // declare tens of millions of them.
        let zero_positions = self.all_zeros(position, Usage::Position, what)?;
        let zero_indices = match prim.indices {
            Some(a) => self.all_zeros(a.value(), Usage::Indices, what)?,
            None => false,
        };
        if zero_positions || zero_indices {
            let (which, a) = match prim.indices {
                Some(a) if zero_indices => ("indices", a.value()),
                _ => ("POSITION", position),
            };
            self.notes.push(format!(
                "{what}: its {which} accessor {a} has neither a bufferView nor sparse values, so it is all zeros and every triangle is degenerate; skipped"
            ));
            return Ok(None);
        }
        let positions = self.read_vec3(position, Usage::Position, what)?;
        let n = positions.len();
        let normals = match attribute(Semantic::Normals) {
            Some(a) => Some(self.read_vec3(a, Usage::Normal, what).and_then(|v| same_count(v, n, a, "NORMAL", what))?),
            None => None,
        };
        let uvs = match attribute(Semantic::TexCoords(0)) {
            Some(a) => {
                let flat = self.read(a, Usage::TexCoord, what, to_f32)?;
                let uvs = flat.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect();
                same_count(uvs, n, a, "TEXCOORD_0", what)?
            }
            None => Vec::new(),
        };
        let indices = match prim.indices {
            Some(a) => self.read_indices(a.value(), n, what)?,
            None => (0..n as u32).collect(),
        };
        Ok(Some(Geometry { positions, normals, uvs, indices }))
    }
}

/// Triangles from a triangle-list, strip or fan index sequence, using the spec's vertex orders (which keep
/// every strip triangle's winding consistent). Also returns the count of leftover list indices.
fn assemble(mode: Mode, idx: &[u32]) -> (Vec<[u32; 3]>, usize) {
    let n = idx.len();
    match mode {
        Mode::TriangleStrip => {
            let tris = (0..n.saturating_sub(2))
                .map(|i| if i % 2 == 0 { [idx[i], idx[i + 1], idx[i + 2]] } else { [idx[i], idx[i + 2], idx[i + 1]] })
                .collect();
            (tris, 0)
        }
        Mode::TriangleFan => ((0..n.saturating_sub(2)).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect(), 0),
        _ => (idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(), n % 3),
    }
}

/// Transforms a primitive to world space, fixes winding for mirrors, drops non-finite triangles and makes
/// every normal unit length. None when no triangle survives.
fn build_mesh(
    mut mesh: Mesh,
    geo: Geometry,
    mut triangles: Vec<[u32; 3]>,
    world: &Mat4,
    notes: &mut Notes,
) -> Option<Mesh> {
    let linear = Mat3::from_mat4(*world);
    let det = linear.determinant();
    if det < 0.0 {
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    mesh.positions = geo.positions.iter().map(|&p| world.transform_point3(p)).collect();
    let before = triangles.len();
    triangles.retain(|t| t.iter().all(|&i| mesh.positions[i as usize].is_finite()));
    let dropped = before - triangles.len();
    notes.dropped_triangles += dropped;
    // The cofactor matrix is the inverse-transpose times det; it exists even for singular transforms,
    // and the sign keeps normals on the side the (possibly mirrored) geometry faces.
    let (c0, c1, c2) = (linear.x_axis, linear.y_axis, linear.z_axis);
    let cofactor = Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1)) * if det < 0.0 { -1.0 } else { 1.0 };
    let provided = geo.normals.is_some();
    mesh.normals = match geo.normals {
        Some(normals) => normals.iter().map(|&n| (cofactor * n).normalize_or_zero()).collect(),
        None => vec![Vec3::ZERO; mesh.positions.len()],
    };
    let repaired = repair_normals(&mesh.positions, &triangles, &mut mesh.normals);
    if provided {
        notes.repaired_normals += repaired;
    }
    mesh.uvs = geo.uvs;
    for uv in mesh.uvs.iter_mut().filter(|uv| !uv.is_finite()) {
        *uv = Vec2::ZERO;
        notes.repaired_uvs += 1;
    }
    mesh.indices = triangles;
    if dropped > 0 {
        compact(&mut mesh);
    }
    (!mesh.indices.is_empty()).then_some(mesh)
}

/// Replaces zero normals by the area-weighted average of the adjacent face normals; returns how many.
fn repair_normals(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut [Vec3]) -> usize {
    let missing = normals.iter().filter(|n| **n == Vec3::ZERO).count();
    if missing == 0 {
        return 0;
    }
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a); // length = twice the area: area weighting for free
        if face.is_finite() {
            t.iter().for_each(|&i| sums[i as usize] += face);
        }
    }
    for (n, sum) in normals.iter_mut().zip(&sums).filter(|(n, _)| **n == Vec3::ZERO) {
        // Vertices no triangle uses (or only degenerate ones) still need a unit normal.
        *n = sum.try_normalize().unwrap_or(Vec3::Z);
    }
    missing
}

/// Removes vertices that no triangle references (after dropping triangles with non-finite vertices).
fn compact(mesh: &mut Mesh) {
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut kept = Vec::new();
    for i in mesh.indices.iter_mut().flatten() {
        if remap[*i as usize] == u32::MAX {
            remap[*i as usize] = kept.len() as u32;
            kept.push(*i as usize);
        }
        *i = remap[*i as usize];
    }
    mesh.positions = kept.iter().map(|&i| mesh.positions[i]).collect();
    mesh.normals = kept.iter().map(|&i| mesh.normals[i]).collect();
    if !mesh.uvs.is_empty() {
        mesh.uvs = kept.iter().map(|&i| mesh.uvs[i]).collect();
    }
}
